#include "mbsflow/io/csv_sink.hpp"

#include <cstdio>

#include "mbsflow/graph/error.hpp"

namespace mbsflow {

void CsvSink::begin(const MultibodySystem& system) {
  system_ = &system;
  out_.open(path_, std::ios::binary);
  if (!out_) throw InputError(path_ + ": cannot write the results file");
  out_ << "t,body,x,y,z,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz\n";
}

void CsvSink::write(double t, const Eigen::VectorXd& y) {
  const StateLayout& l = system_->layout();
  char buf[40];
  auto put = [&](double v) {
    std::snprintf(buf, sizeof buf, ",%.17g", v);
    out_ << buf;
  };
  for (Eigen::Index i = 0; i < l.bodies; ++i) {
    std::snprintf(buf, sizeof buf, "%.17g", t);
    out_ << buf << ',' << system_->model().bodies[static_cast<std::size_t>(i)].name;
    for (Eigen::Index k = 0; k < 3; ++k) put(y[l.position(i) + k]);
    for (Eigen::Index k = 0; k < 4; ++k) put(y[l.orientation(i) + k]);
    for (Eigen::Index k = 0; k < 3; ++k) put(y[l.velocity(i) + k]);
    for (Eigen::Index k = 0; k < 3; ++k) put(y[l.angular_velocity(i) + k]);
    out_ << '\n';
  }
}

void CsvSink::end() {
  if (out_.is_open()) out_.close();
}

}  // namespace mbsflow
