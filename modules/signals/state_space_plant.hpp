// A linear time-invariant plant  x' = A x + B u,  y = C x + D u  run on the process-data
// cycle, so that e.g. an analog output driving a heater moves a thermocouple reading.
//
// The continuous model is discretised once for the cycle time dt with a zero-order hold on
// u (the outputs hold their value between frames):  Ad = e^(A dt),
// Bd = ∫0..dt e^(A s) ds B, both read off one matrix exponential of the augmented matrix
// [[A B] [0 0]] dt (Van Loan). step() then only does two matrix-vector products into
// preallocated vectors: no allocation on the cyclic path.
#pragma once

#include <Eigen/Dense>
#include <cstddef>
#include <string>
#include <vector>

namespace rackcat::modules {

class StateSpacePlant {
 public:
  // A: n×n, B: n×m, C: p×n, D: p×m (empty D = zero). Throws std::invalid_argument on
  // inconsistent dimensions or dt <= 0.
  StateSpacePlant(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b, Eigen::MatrixXd c,
                  Eigen::MatrixXd d, double dt);

  size_t states() const { return static_cast<size_t>(ad_.rows()); }
  size_t inputs() const { return static_cast<size_t>(bd_.cols()); }
  size_t outputs() const { return static_cast<size_t>(c_.rows()); }
  double dt() const { return dt_; }

  // Bind input k to a value that the plant reads every step (an output channel's live
  // value). Unbound inputs read the value given by set_input().
  void bind_input(size_t k, const double* source);
  void set_input(size_t k, double value);
  void set_state(const Eigen::VectorXd& x);

  // One cycle: read u, compute y = C x + D u for this instant, then advance x by dt.
  void step();

  double output(size_t i) const { return y_[static_cast<Eigen::Index>(i)]; }
  const Eigen::VectorXd& state() const { return x_; }
  const Eigen::MatrixXd& ad() const { return ad_; }
  const Eigen::MatrixXd& bd() const { return bd_; }

 private:
  Eigen::MatrixXd ad_, bd_, c_, d_;
  Eigen::VectorXd x_, x_next_, u_, y_;
  std::vector<const double*> bound_;
  double dt_;
};

}  // namespace rackcat::modules
