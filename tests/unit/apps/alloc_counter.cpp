// The counting operator new shared by every test executable.
#include "support/alloc_counter_impl.hpp"
