#include "modal.hpp"

#include <Eigen/OrderingMethods>
#include <Eigen/QR>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <Spectra/SymEigsSolver.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

namespace mesopen::fem {

namespace {

using Clock = std::chrono::steady_clock;
using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

// Sparse Cholesky L L^T with the approximate-minimum-degree fill-reducing ordering. Measured on
// the 20,000-node projectile: as fast as CHOLMOD's simplicial factor, faster than its supernodal
// one over the reference BLAS; METIS orders no better there (docs/modal.md).
using Cholesky = Eigen::SimplicialLLT<SparseMatrix, Eigen::Lower, Eigen::AMDOrdering<int>>;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// The plane elasticity matrix D (sigma = D eps, engineering shear strain) from K and G:
// plane strain D = [[l + 2G, l, 0], [l, l + 2G, 0], [0, 0, G]], l = K - 2G/3 (Lame);
// plane stress the same with l* = 2 l G / (l + 2G) (sigma_zz = 0 eliminated).
struct PlaneElasticity {
  double d11, d12, d33;
};

PlaneElasticity planeElasticity(const ElasticSolid &s) {
  const double g = s.shear_modulus;
  double lambda = s.bulk_modulus - 2.0 * g / 3.0;
  if (s.plane == PlaneModel::stress)
    lambda = 2.0 * lambda * g / (lambda + 2.0 * g);
  return {lambda + 2.0 * g, lambda, g};
}

// Stiffness (lower triangle, free unknowns only) and lumped mass per unknown.
struct System {
  SparseMatrix stiffness;   // lower triangle
  std::vector<double> mass; // per free unknown [kg/m]
  std::vector<int> unknown; // per dof (2 a + c): its free unknown, or -1 when fixed
  double total_mass = 0.0;
};

// CST stiffness K_e = A B^T D B (thesis appendix C), with B = 1/(2A) [[y23, 0, y31, 0, y12, 0],
// [0, x32, 0, x13, 0, x21], [x32, y23, x13, y31, x21, y12]], y_ij = y_i - y_j; lumped mass
// rho A / 3 per node and direction.
System assemble(const ModalMesh &mesh, const ElasticSolid &solid) {
  const std::size_t n_nodes = mesh.nodes(), n_tri = mesh.triangles();
  if (!mesh.fixed.empty() && mesh.fixed.size() != n_nodes)
    throw std::invalid_argument("modal: fixed flags for " + std::to_string(mesh.fixed.size()) +
                                " nodes, the mesh has " + std::to_string(n_nodes));
  System sys;
  sys.unknown.assign(2 * n_nodes, -1);
  int n = 0;
  for (std::size_t a = 0; a < n_nodes; ++a)
    if (mesh.fixed.empty() || !mesh.fixed[a])
      sys.unknown[2 * a] = n++, sys.unknown[2 * a + 1] = n++;
  sys.mass.assign(n, 0.0);
  const PlaneElasticity d = planeElasticity(solid);

  std::vector<Eigen::Triplet<double, int>> entries;
  entries.reserve(21 * n_tri);
  for (std::size_t e = 0; e < n_tri; ++e) {
    const std::uint32_t *v = &mesh.tri[3 * e];
    const double x1 = mesh.x[v[0]], x2 = mesh.x[v[1]], x3 = mesh.x[v[2]];
    const double y1 = mesh.y[v[0]], y2 = mesh.y[v[1]], y3 = mesh.y[v[2]];
    const double area = 0.5 * ((x2 - x1) * (y3 - y1) - (x3 - x1) * (y2 - y1));
    if (!(area > 0.0))
      throw std::invalid_argument("modal: triangle " + std::to_string(e) +
                                  " is not counter-clockwise (area " + std::to_string(area) +
                                  " m^2)");
    // Shape-function gradients: dN_i/dx = b_i / 2A, dN_i/dy = c_i / 2A.
    const double b[3] = {y2 - y3, y3 - y1, y1 - y2};
    const double c[3] = {x3 - x2, x1 - x3, x2 - x1};
    const double scale = 1.0 / (4.0 * area);
    double k[6][6];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        k[2 * i][2 * j] = scale * (d.d11 * b[i] * b[j] + d.d33 * c[i] * c[j]);
        k[2 * i][2 * j + 1] = scale * (d.d12 * b[i] * c[j] + d.d33 * c[i] * b[j]);
        k[2 * i + 1][2 * j] = scale * (d.d12 * c[i] * b[j] + d.d33 * b[i] * c[j]);
        k[2 * i + 1][2 * j + 1] = scale * (d.d11 * c[i] * c[j] + d.d33 * b[i] * b[j]);
      }
    int dof[6];
    for (int i = 0; i < 3; ++i)
      dof[2 * i] = sys.unknown[2 * v[i]], dof[2 * i + 1] = sys.unknown[2 * v[i] + 1];
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j < 6; ++j)
        if (dof[i] >= 0 && dof[j] >= 0 && dof[i] >= dof[j])
          entries.emplace_back(dof[i], dof[j], k[i][j]);
    const double node_mass = solid.density * area / 3.0;
    sys.total_mass += 3.0 * node_mass;
    for (int i = 0; i < 6; ++i)
      if (dof[i] >= 0)
        sys.mass[dof[i]] += node_mass;
  }
  sys.stiffness.resize(n, n);
  sys.stiffness.setFromTriplets(entries.begin(), entries.end());
  return sys;
}

// The shift-invert operation on the mass-scaled problem, scaled to eigenvalues in (0, 1]:
//   y = |sigma| P M^1/2 (K - sigma M)^-1 M^1/2 P x,
// P the projection out of the rigid-body motions (orthonormal columns of `rigid`, mass-scaled).
// An eigenvalue theta of it is lambda = |sigma| / theta + sigma. (Without the factor |sigma| the
// operator's eigenvalues are ~1e-14 s^2 for the projectile, below the absolute thresholds of
// Spectra's Lanczos, which then returned wrong modes for some densities.)
class ShiftInvert {
public:
  using Scalar = double;

  ShiftInvert(const SparseMatrix &stiffness, const std::vector<double> &mass, Eigen::MatrixXd rigid)
      : k_(stiffness), rigid_(std::move(rigid)) {
    sqrt_mass_.resize(static_cast<Eigen::Index>(mass.size()));
    for (std::size_t i = 0; i < mass.size(); ++i)
      sqrt_mass_[static_cast<Eigen::Index>(i)] = std::sqrt(mass[i]);
  }
  Eigen::Index rows() const { return sqrt_mass_.size(); }
  Eigen::Index cols() const { return sqrt_mass_.size(); }

  // Factor K - sigma M (sigma < 0: positive definite).
  void factor(double sigma) {
    scale_ = -sigma;
    SparseMatrix shifted = k_;
    for (Eigen::Index i = 0; i < rows(); ++i)
      shifted.coeffRef(i, i) -= sigma * sqrt_mass_[i] * sqrt_mass_[i];
    solver_.compute(shifted);
    if (solver_.info() != Eigen::Success)
      throw std::runtime_error("modal: the Cholesky factorisation of K - sigma M failed (a body "
                               "that is not connected, or a mechanism)");
  }

  void perform_op(const double *x_in, double *y_out) const {
    Eigen::Map<const Eigen::VectorXd> x(x_in, rows());
    Eigen::Map<Eigen::VectorXd> y(y_out, rows());
    Eigen::VectorXd v = project(x);
    v = solver_.solve(v.cwiseProduct(sqrt_mass_)).cwiseProduct(sqrt_mass_);
    y = scale_ * project(v);
    ++operations_;
  }

  long operations() const { return operations_; }
  std::size_t factorNonzeros() const {
    return static_cast<std::size_t>(solver_.matrixL().nestedExpression().nonZeros());
  }

private:
  Eigen::VectorXd project(const Eigen::VectorXd &v) const {
    if (rigid_.cols() == 0)
      return v;
    return v - rigid_ * (rigid_.transpose() * v);
  }

  const SparseMatrix &k_;
  Eigen::MatrixXd rigid_;
  Eigen::VectorXd sqrt_mass_;
  Cholesky solver_;
  double scale_ = 1.0;
  mutable long operations_ = 0;
};

// Rigid-body motions of a free body in mass-scaled form (columns M^1/2 r, orthonormal): x and y
// translation and the rotation about the centre of mass (-(y - y_c), x - x_c).
Eigen::MatrixXd rigidMotions(const ModalMesh &mesh, const System &sys) {
  const std::size_t n_nodes = mesh.nodes();
  double xc = 0.0, yc = 0.0, m = 0.0;
  for (std::size_t a = 0; a < n_nodes; ++a) {
    const double ma = sys.mass[sys.unknown[2 * a]];
    xc += ma * mesh.x[a], yc += ma * mesh.y[a], m += ma;
  }
  xc /= m, yc /= m;
  Eigen::MatrixXd r = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(sys.mass.size()), 3);
  for (std::size_t a = 0; a < n_nodes; ++a) {
    const int u = sys.unknown[2 * a], v = sys.unknown[2 * a + 1];
    const double s = std::sqrt(sys.mass[u]);
    r(u, 0) = s;
    r(v, 1) = s;
    r(u, 2) = -s * (mesh.y[a] - yc);
    r(v, 2) = s * (mesh.x[a] - xc);
  }
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(r);
  return qr.householderQ() * Eigen::MatrixXd::Identity(r.rows(), 3);
}

} // namespace

ModalResult freeVibration(const ModalMesh &mesh, const ElasticSolid &solid,
                          const ModalSettings &settings) {
  ModalResult result;
  auto start = Clock::now();
  const System sys = assemble(mesh, solid);
  const auto n = static_cast<int>(sys.mass.size());
  const bool free_body = n == static_cast<int>(2 * mesh.nodes());
  result.rigid_modes = free_body ? 3 : 0;
  result.mass = sys.total_mass;
  result.unknowns = static_cast<std::size_t>(n);
  const int wanted = settings.modes;
  if (wanted < 1 || wanted + result.rigid_modes + 2 > n)
    throw std::invalid_argument("modal: " + std::to_string(wanted) +
                                " modes asked of a mesh with " + std::to_string(n) +
                                " free unknowns");
  const Eigen::MatrixXd rigid = free_body ? rigidMotions(mesh, sys) : Eigen::MatrixXd(n, 0);
  result.assemble_seconds = secondsSince(start);

  // sigma < 0, far below the lowest elastic eigenvalue and still well conditioned: 1e-8 of the
  // largest diagonal ratio K_ii / M_ii, which bounds the largest eigenvalue to within a small
  // factor (Gershgorin).
  double largest = 0.0;
  for (int i = 0; i < n; ++i)
    largest = std::max(largest, sys.stiffness.coeff(i, i) / sys.mass[i]);
  result.shift = -1e-8 * largest;

  start = Clock::now();
  ShiftInvert op(sys.stiffness, sys.mass, rigid);
  const int ncv =
      std::min(n - result.rigid_modes, settings.lanczos > 0 ? settings.lanczos : 2 * wanted + 1);
  op.factor(result.shift);
  Spectra::SymEigsSolver<ShiftInvert> eigs(op, wanted, ncv);
  result.factor_seconds = secondsSince(start);
  result.factor_nonzeros = op.factorNonzeros();

  start = Clock::now();
  // A deterministic start vector with no rigid-body part.
  Eigen::VectorXd v0(n);
  for (int i = 0; i < n; ++i)
    v0[i] = 1.0 + 0.5 * std::sin(0.7 * i) + 0.25 * std::cos(1.3 * i);
  if (rigid.cols() > 0)
    v0 -= rigid * (rigid.transpose() * v0);
  eigs.init(v0.data());
  eigs.compute(Spectra::SortRule::LargestAlge, 1000, settings.tolerance);
  if (eigs.info() != Spectra::CompInfo::Successful)
    throw std::runtime_error("modal: the Lanczos iteration did not converge (" +
                             std::to_string(eigs.num_iterations()) + " restarts)");
  const Eigen::VectorXd theta = eigs.eigenvalues();
  Eigen::VectorXd lambda(theta.size());
  for (Eigen::Index k = 0; k < theta.size(); ++k)
    lambda[k] = -result.shift / theta[k] + result.shift;
  const Eigen::MatrixXd y = eigs.eigenvectors();
  result.solve_seconds = secondsSince(start);
  result.operations = op.operations();

  std::vector<int> order(static_cast<std::size_t>(lambda.size()));
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return lambda[a] < lambda[b]; });
  for (int k : order) {
    result.omega.push_back(std::sqrt(std::max(0.0, lambda[k])));
    std::vector<double> shape(2 * mesh.nodes(), 0.0);
    for (std::size_t dof = 0; dof < shape.size(); ++dof)
      if (sys.unknown[dof] >= 0)
        shape[dof] = y(sys.unknown[dof], k) / std::sqrt(sys.mass[sys.unknown[dof]]);
    result.shapes.push_back(std::move(shape));
  }
  // The rigid motions' Rayleigh quotients r^T K r / r^T M r (r mass-scaled back: M^-1/2 q).
  for (Eigen::Index j = 0; j < rigid.cols(); ++j) {
    Eigen::VectorXd r = rigid.col(j);
    for (int i = 0; i < n; ++i)
      r[i] /= std::sqrt(sys.mass[i]);
    const Eigen::VectorXd kr = sys.stiffness.selfadjointView<Eigen::Lower>() * r;
    double rmr = 0.0;
    for (int i = 0; i < n; ++i)
      rmr += sys.mass[i] * r[i] * r[i];
    result.rigid_omega.push_back(std::sqrt(std::abs(r.dot(kr)) / rmr));
  }
  return result;
}

std::vector<double> lumpedMass(const ModalMesh &mesh, double density) {
  std::vector<double> mass(mesh.nodes(), 0.0);
  for (std::size_t e = 0; e < mesh.triangles(); ++e) {
    const std::uint32_t *v = &mesh.tri[3 * e];
    const double area = 0.5 * ((mesh.x[v[1]] - mesh.x[v[0]]) * (mesh.y[v[2]] - mesh.y[v[0]]) -
                               (mesh.x[v[2]] - mesh.x[v[0]]) * (mesh.y[v[1]] - mesh.y[v[0]]));
    for (int i = 0; i < 3; ++i)
      mass[v[i]] += density * area / 3.0;
  }
  return mass;
}

double directionShare(const ModalMesh &mesh, const ElasticSolid &solid,
                      const std::vector<double> &shape, double angle) {
  const std::vector<double> mass = lumpedMass(mesh, solid.density);
  const double ex = std::cos(angle), ey = std::sin(angle);
  double along = 0.0, all = 0.0;
  for (std::size_t a = 0; a < mesh.nodes(); ++a) {
    const double ux = shape[2 * a], uy = shape[2 * a + 1], p = ux * ex + uy * ey;
    along += mass[a] * p * p;
    all += mass[a] * (ux * ux + uy * uy);
  }
  return all > 0.0 ? along / all : 0.0;
}

} // namespace mesopen::fem
