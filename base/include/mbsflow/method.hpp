#pragma once
// The name of an integration method. Which names exist is the stepper registry's business
// (mbsflow/methods/stepper.hpp: find_method, stepper_entries); a Method is only the name,
// so that the model (graph/) can carry one without knowing the methods.
#include <cstring>

namespace mbsflow {

class Method {
 public:
  // name must outlive the Method: a string literal or a registry entry's name.
  constexpr explicit Method(const char* name = "rk4") : name_(name) {}
  constexpr const char* name() const { return name_; }
  friend bool operator==(const Method& a, const Method& b) { return std::strcmp(a.name_, b.name_) == 0; }

  // The methods every build has.
  static const Method rk4, dopri5, colloc, tirk;

 private:
  const char* name_;
};

inline constexpr Method Method::rk4{"rk4"};
inline constexpr Method Method::dopri5{"dopri5"};
inline constexpr Method Method::colloc{"colloc"};
inline constexpr Method Method::tirk{"tirk"};

inline const char* method_name(Method m) { return m.name(); }

}  // namespace mbsflow
