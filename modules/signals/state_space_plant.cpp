#include "modules/signals/state_space_plant.hpp"

#include <stdexcept>
#include <unsupported/Eigen/MatrixFunctions>

namespace rackcat::modules {

StateSpacePlant::StateSpacePlant(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b,
                                 Eigen::MatrixXd c, Eigen::MatrixXd d, double dt)
    : dt_(dt) {
  const Eigen::Index n = a.rows();
  if (n == 0 || a.cols() != n) throw std::invalid_argument("plant: A must be square, n >= 1");
  if (b.rows() != n || b.cols() == 0) throw std::invalid_argument("plant: B must be n x m");
  const Eigen::Index m = b.cols();
  if (c.cols() != n || c.rows() == 0) throw std::invalid_argument("plant: C must be p x n");
  const Eigen::Index p = c.rows();
  if (d.size() == 0) d = Eigen::MatrixXd::Zero(p, m);
  if (d.rows() != p || d.cols() != m) throw std::invalid_argument("plant: D must be p x m");
  if (!(dt > 0.0)) throw std::invalid_argument("plant: cycle time must be > 0");

  // Van Loan: exp([[A B] [0 0]] dt) = [[Ad Bd] [0 I]].
  Eigen::MatrixXd aug = Eigen::MatrixXd::Zero(n + m, n + m);
  aug.topLeftCorner(n, n) = a * dt;
  aug.topRightCorner(n, m) = b * dt;
  const Eigen::MatrixXd e = aug.exp();
  ad_ = e.topLeftCorner(n, n);
  bd_ = e.topRightCorner(n, m);
  c_ = std::move(c);
  d_ = std::move(d);
  x_ = Eigen::VectorXd::Zero(n);
  x_next_ = Eigen::VectorXd::Zero(n);
  u_ = Eigen::VectorXd::Zero(m);
  y_ = Eigen::VectorXd::Zero(p);
  bound_.assign(static_cast<size_t>(m), nullptr);
}

void StateSpacePlant::bind_input(size_t k, const double* source) {
  if (k >= bound_.size()) throw std::out_of_range("plant: input index");
  bound_[k] = source;
}

void StateSpacePlant::set_input(size_t k, double value) {
  if (k >= bound_.size()) throw std::out_of_range("plant: input index");
  u_[static_cast<Eigen::Index>(k)] = value;
}

void StateSpacePlant::set_state(const Eigen::VectorXd& x) {
  if (x.size() != x_.size()) throw std::invalid_argument("plant: state size");
  x_ = x;
}

void StateSpacePlant::step() {
  for (size_t k = 0; k < bound_.size(); ++k) {
    if (bound_[k] != nullptr) u_[static_cast<Eigen::Index>(k)] = *bound_[k];
  }
  y_.noalias() = c_ * x_;
  y_.noalias() += d_ * u_;
  x_next_.noalias() = ad_ * x_;
  x_next_.noalias() += bd_ * u_;
  x_.swap(x_next_);
}

}  // namespace rackcat::modules
