// The "colloc" stepper: collocation block methods with the seed's s/(s+1)-point step
// control (BlockIntegrator). variant "m,s" or "m,s,order" picks the method (default 1,2).
// Dense output from the accepted block's collocation polynomial.
#include <cstdio>

#include "mbsflow/methods/block_integrator.hpp"
#include "stepper_registry.hpp"
#include "stepper_system.hpp"

namespace mbsflow {
namespace {

BlockMethodSpec parse_spec(const std::string& v) {
  BlockMethodSpec spec;
  if (v.empty()) return spec;
  int order = 0;
  char end = 0;
  const int n = std::sscanf(v.c_str(), "%d,%d,%d%c", &spec.m, &spec.s, &order, &end);
  if (n != 2 && n != 3) throw InputError("colloc: the variant is m,s or m,s,order (got '" + v + "')");
  spec.order = order;
  return spec;
}

class CollocStepper final : public Stepper {
 public:
  CollocStepper(const StepperSystem& s, const StepperSettings& o) : problem_(problem_of(s)) {
    check_system(s);
    settings_.method = parse_spec(o.variant);
    generate_block_method(settings_.method);  // InputError for a method that does not exist
    settings_.rtol = o.rtol;
    settings_.atol = o.atol;
    settings_.threads = o.threads;
    settings_.initial_step = o.step;
    settings_.finite_difference_jacobian = !s.jacobian;
    integrator_ = std::make_unique<BlockIntegrator>(
        problem_, settings_, [this](const AcceptedBlock& b) { keep(b); }, s.after_step);
  }
  void start(double t, const Eigen::VectorXd& y, double t_end) override {
    problem_.t0 = t;
    problem_.t_end = t_end;
    problem_.y0 = y;
    if (started_) settings_.initial_step = integrator_->next_step();
    started_ = true;
    integrator_->begin();
    t_ = t_previous_ = t;
    t_end_ = t_end;
    y_ = y;
    count();
  }
  void step() override {
    if (!integrator_->advance()) return;
    t_previous_ = t_;
    t_ = integrator_->t();
    y_ = integrator_->y();
    count();
  }
  void dense(double t, Eigen::VectorXd& out) const override { out = last_.view().interpolate(t); }
  double next_step() const override { return integrator_->next_step(); }
  void set_next_step(double h) override { settings_.initial_step = h; }

 private:
  struct Block {  // a copy of the last accepted block, for dense output
    const BlockCoefficients* method = nullptr;
    double t0 = 0, tau = 0;
    std::vector<Eigen::VectorXd> past_u, past_f, u, f;
    AcceptedBlock view() const { return {t0, tau, static_cast<int>(u.size()), method, &past_u, &past_f, &u, &f}; }
  };
  void keep(const AcceptedBlock& b) {
    last_ = {b.method, b.t0, b.tau, *b.past_u, *b.past_f, *b.u, *b.f};
  }
  void count() {
    const BlockStats& st = integrator_->stats();
    stats_.accepted = st.accepted;
    stats_.rejected = st.rejected;
    stats_.evaluations = st.rhs_evaluations;
  }

  OdeProblem problem_;
  BlockSettings settings_;
  std::unique_ptr<BlockIntegrator> integrator_;
  Block last_;
  bool started_ = false;
};

}  // namespace

std::unique_ptr<Stepper> make_colloc_stepper(const StepperSystem& s, const StepperSettings& o) {
  return std::make_unique<CollocStepper>(s, o);
}

}  // namespace mbsflow
