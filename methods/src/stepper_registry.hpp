#pragma once
// The factories the registry lists, one per method file.
#include "mbsflow/methods/stepper.hpp"

namespace mbsflow {
std::unique_ptr<Stepper> make_rk4_stepper(const StepperSystem& s, const StepperSettings& o);
std::unique_ptr<Stepper> make_dopri5_stepper(const StepperSystem& s, const StepperSettings& o);
std::unique_ptr<Stepper> make_colloc_stepper(const StepperSystem& s, const StepperSettings& o);
std::unique_ptr<Stepper> make_tirk_stepper(const StepperSystem& s, const StepperSettings& o);
}  // namespace mbsflow
