#pragma once
// Tick marks a reader can add up: steps of 1, 2 or 5 times a power of ten,
// ticks on the multiples of the step, labels with just the decimals the
// step needs.
#include <string>
#include <vector>

namespace rtfuse::apps {

// The smallest step of the form {1, 2, 5} x 10^k that is at least `least`.
// A non-positive or non-finite `least` gives 1.
double nice_step_at_least(double least);

// The smallest 1-2-5 step that splits `span` into at most `max_intervals`
// intervals (max_intervals < 1 is taken as 1).
double nice_step(double span, int max_intervals);

// The step after `step` in the 1-2-5 series (1 -> 2 -> 5 -> 10 ...).
double next_nice_step(double step);

// The multiples of step within [lo, hi] (a rounding error's worth of slack
// at either end), ascending; at most 1000 of them. Empty for a step that is
// not positive and finite or a range that is not finite.
std::vector<double> tick_values(double lo, double hi, double step);

// A tick's label: as many decimals as the step has (step 0.5 -> "2.5",
// step 20 -> "40", step 0.05 -> "0.15"), and "0" rather than "-0" for a tick
// at zero that rounding put just below it.
std::string tick_label(double value, double step);

}  // namespace rtfuse::apps
