// Free vibration of a plane elastic body (thesis section 5.9, Eq. 5.1, appendices B and C):
//   K phi = omega^2 M phi,
// K the constant-strain-triangle stiffness (plane strain or plane stress, 1 m thick), M the lumped
// mass (a third of each element's mass at each of its nodes, as in the explicit solver). omega is
// an angular frequency [rad/s]; f = omega / 2 pi [Hz] (the thesis prints omega under the label
// Hz).
//
// The solver: with the diagonal M, the problem is the standard symmetric one
//   A y = lambda y,  A = M^-1/2 K M^-1/2,  y = M^1/2 phi,  lambda = omega^2,
// solved by Lanczos (Spectra) in shift-invert mode, (A - sigma I)^-1 = M^1/2 (K - sigma M)^-1
// M^1/2, with sigma < 0 so that K - sigma M is positive definite and has a sparse Cholesky factor
// (Eigen's simplicial L L^T, AMD ordering). For a free body the three rigid-body motions (two
// translations, the rotation about the centre of mass) are projected out of every Lanczos vector,
// so the modes found are the elastic ones only.
#pragma once

#include <cstdint>
#include <vector>

namespace mesopen::fem {

// A triangle mesh (counter-clockwise triangles) and the nodes held fixed (empty: a free body).
struct ModalMesh {
  std::vector<double> x, y;        // node positions [m]
  std::vector<std::uint32_t> tri;  // 3 node indices per triangle
  std::vector<std::uint8_t> fixed; // per node, 1: both displacements held at 0 (or empty)
  std::size_t nodes() const { return x.size(); }
  std::size_t triangles() const { return tri.size() / 3; }
};

enum class PlaneModel { strain, stress };

// Isotropic linear elasticity: the 3D moduli and how the plane is taken (plane strain: eps_zz = 0;
// plane stress: sigma_zz = 0).
struct ElasticSolid {
  double density = 7823.0;       // rho [kg/m^3]
  double bulk_modulus = 163.9e9; // K [Pa]
  double shear_modulus = 77.5e9; // G [Pa]
  PlaneModel plane = PlaneModel::strain;
  double youngs_modulus() const {
    return 9.0 * bulk_modulus * shear_modulus / (3.0 * bulk_modulus + shear_modulus);
  }
  double poisson_ratio() const {
    return (3.0 * bulk_modulus - 2.0 * shear_modulus) /
           (2.0 * (3.0 * bulk_modulus + shear_modulus));
  }
};

struct ModalSettings {
  int modes = 10;  // elastic modes wanted (lowest)
  int lanczos = 0; // Lanczos basis size (Spectra's ncv); 0: 2 modes + 1 (Spectra's advice)
  // Relative residual of the Ritz pairs, |A y - theta y| <= tol |theta|: the eigenvalues are then
  // accurate to about tol^2 (Rayleigh quotient), the shapes to about tol.
  double tolerance = 1e-6;
};

struct ModalResult {
  std::vector<double> omega; // angular frequencies, ascending [rad/s]
  // Mode shapes, mass-normalised (phi^T M phi = 1 with M per metre [kg/m]): mode k's x and y
  // displacement of node a are shapes[k][2a], shapes[k][2a + 1] (0 at fixed nodes).
  std::vector<std::vector<double>> shapes;
  // The rigid-body motions projected out (3 for a free body, none otherwise) and their Rayleigh
  // quotients sqrt(r^T K r / r^T M r) [rad/s]: zero but for rounding, a check of K.
  int rigid_modes = 0;
  std::vector<double> rigid_omega;
  double mass = 0.0;        // total mass [kg/m]
  std::size_t unknowns = 0; // free degrees of freedom
  std::size_t factor_nonzeros = 0;
  double shift = 0.0;  // sigma [rad^2/s^2]
  long operations = 0; // shift-invert solves
  double assemble_seconds = 0.0, factor_seconds = 0.0, solve_seconds = 0.0;
};

// The lowest `settings.modes` elastic modes. Throws std::invalid_argument for a bad mesh
// (an inverted triangle, fewer unknowns than modes) and std::runtime_error when the
// factorisation or the eigen solver fails.
ModalResult freeVibration(const ModalMesh &mesh, const ElasticSolid &solid,
                          const ModalSettings &settings = {});

// The lumped nodal masses [kg/m]: rho A / 3 of every triangle at each of its nodes.
std::vector<double> lumpedMass(const ModalMesh &mesh, double density);

// How much of mode k's kinetic energy moves along the direction (cos a, sin a): sum over nodes of
// m (phi . e)^2 over sum m |phi|^2. With e along a beam's axis: near 1 for an axial mode, near 0
// for a bending mode.
double directionShare(const ModalMesh &mesh, const ElasticSolid &solid,
                      const std::vector<double> &shape, double angle);

} // namespace mesopen::fem
