#include "support/alloc_counter_impl.hpp"
