// The "tirk" stepper: implicit Runge-Kutta (TirkIntegrator). The variant is a
// comma-separated list of a tableau name (default radau3) and/or an iteration name
// (default newton, as Radau5; newton-triangular is the seed's PTIRK), in any order: "radau5", "newton",
// "radau3,newton-diagonal".
#include "mbsflow/methods/tirk_integrator.hpp"

#include <algorithm>
#include <sstream>

#include "stepper_registry.hpp"
#include "implicit_stepper.hpp"

namespace mbsflow {
namespace {

class TirkStepper final : public ImplicitStepper<TirkIntegrator, TirkSettings> {
 public:
  TirkStepper(const StepperSystem& s, const StepperSettings& o) : ImplicitStepper(s, o) {
    apply_variant(o.variant);
    rk_tableau(settings_.tableau);  // InputError for an unknown tableau
    integrator_ = std::make_unique<TirkIntegrator>(problem_, settings_, s.after_step);
  }
  void dense(double t, Eigen::VectorXd& out) const override { integrator_->dense(t, out); }

 private:
  void apply_variant(const std::string& variant) {
    const std::vector<std::string> tableaux = rk_tableau_names();
    std::stringstream in(variant);
    for (std::string token; std::getline(in, token, ',');) {
      if (std::find(tableaux.begin(), tableaux.end(), token) != tableaux.end()) {
        settings_.tableau = token;
      } else {
        try {
          settings_.iteration = tirk_iteration_from_string(token);
        } catch (const InputError&) {
          throw InputError("tirk: the variant '" + variant + "' names neither a tableau nor an iteration: '" + token + "'");
        }
      }
    }
  }
};

}  // namespace

std::unique_ptr<Stepper> make_tirk_stepper(const StepperSystem& s, const StepperSettings& o) {
  return std::make_unique<TirkStepper>(s, o);
}

}  // namespace mbsflow
