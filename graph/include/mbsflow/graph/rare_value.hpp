#pragma once
// A member that most items leave at its default (a joint's motor and limits), held behind
// one pointer so that a million such items stay small: it reads as the default while
// empty, copies as a value, and makes room when written through edit().
#include <memory>

namespace mbsflow {

template <class T>
class RareValue {
 public:
  RareValue() = default;
  RareValue(const RareValue& o) : p_(o.p_ ? std::make_unique<T>(*o.p_) : nullptr) {}
  RareValue& operator=(const RareValue& o) {
    if (this != &o) p_ = o.p_ ? std::make_unique<T>(*o.p_) : nullptr;
    return *this;
  }
  RareValue(RareValue&&) noexcept = default;
  RareValue& operator=(RareValue&&) noexcept = default;

  const T& get() const { return p_ ? *p_ : fallback(); }
  const T* operator->() const { return &get(); }
  T& edit() {
    if (!p_) p_ = std::make_unique<T>();
    return *p_;
  }

 private:
  static const T& fallback() {
    static const T value{};
    return value;
  }
  std::unique_ptr<T> p_;
};

}  // namespace mbsflow
