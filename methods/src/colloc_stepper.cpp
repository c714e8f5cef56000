// The "colloc" stepper: collocation block methods with the seed's s/(s+1)-point step
// control (BlockIntegrator). variant "radau" or "radau,s" (blocks at Radau points; the
// default, s = 3) or "m,s" / "m,s,order" (the seed's equidistant blocks) picks the method.
// Dense output from the accepted block's collocation polynomial.
#include "mbsflow/methods/block_integrator.hpp"
#include "stepper_registry.hpp"
#include "implicit_stepper.hpp"

namespace mbsflow {
namespace {

class CollocStepper final : public ImplicitStepper<BlockIntegrator, BlockSettings> {
 public:
  CollocStepper(const StepperSystem& s, const StepperSettings& o) : ImplicitStepper(s, o) {
    settings_.method = parse_block_method(o.variant);  // InputError for a method that does not exist
    integrator_ = std::make_unique<BlockIntegrator>(
        problem_, settings_, [this](const AcceptedBlock& b) { keep(b); }, s.after_step);
  }
  void dense(double t, Eigen::VectorXd& out) const override { out = last_.view().interpolate(t); }

 private:
  struct Block {  // a copy of the last accepted block, for dense output
    const BlockCoefficients* method = nullptr;
    double t0 = 0, tau = 0;
    std::vector<Eigen::VectorXd> past_u, past_f, u, f;
    AcceptedBlock view() const { return {t0, tau, static_cast<int>(u.size()), method, &past_u, &past_f, &u, &f}; }
  };
  void keep(const AcceptedBlock& b) { last_ = {b.method, b.t0, b.tau, *b.past_u, *b.past_f, *b.u, *b.f}; }

  Block last_;
};

}  // namespace

std::unique_ptr<Stepper> make_colloc_stepper(const StepperSystem& s, const StepperSettings& o) {
  return std::make_unique<CollocStepper>(s, o);
}

}  // namespace mbsflow
