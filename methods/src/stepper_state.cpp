// What every stepper keeps in a checkpoint: time, state, end and counters; the method's
// own part follows (save_method / restore_method).
#include "mbsflow/methods/stepper.hpp"

#include <cstdint>

namespace mbsflow {

void Stepper::save(StateWriter& out) const {
  out.text("stepper");
  out.real(t_);
  out.real(t_previous_);
  out.real(t_end_);
  out.vector(y_);
  for (long v : {stats_.accepted, stats_.rejected, stats_.evaluations, stats_.jacobians, stats_.factorizations}) out.integer(v);
  save_method(out);
}

void Stepper::restore(StateReader& in) {
  in.expect("stepper");
  t_ = in.real();
  t_previous_ = in.real();
  t_end_ = in.real();
  y_ = in.vector(y_.size());  // restore() follows a start(), which sized the state
  for (long* v : {&stats_.accepted, &stats_.rejected, &stats_.evaluations, &stats_.jacobians, &stats_.factorizations})
    *v = in.integer(0, INT64_MAX);
  restore_method(in);
}

}  // namespace mbsflow
