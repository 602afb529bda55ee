// The one translation unit of rtfuse_unit_hal that replaces operator new/delete.
#include "support/alloc_counter_impl.hpp"
