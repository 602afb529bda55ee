// The same counting operator new as the core tests, compiled into this
// executable too (each test executable needs its own replacement).
#include "unit/core/alloc_counter.cpp"
