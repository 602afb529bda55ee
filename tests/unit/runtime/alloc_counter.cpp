// The one translation unit of this executable that replaces global operator new.
#include "support/alloc_counter_impl.hpp"
