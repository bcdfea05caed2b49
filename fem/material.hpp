// Materials: each updates the stress of a batch of elements from their rate of deformation
// (thesis section 3.3). The split is sigma = -p I + S; the deviator S follows an objective
// (Jaumann) rate, or for purely elastic materials derives from a stored energy and F
// (materials/hyperelastic.hpp), the pressure an equation of state, and the internal energy the
// energy equation
//   dE = V S:D dt - p dV   (plane strain per metre, V an area)
// integrated with the mean of the old and new stress (the pressure implicitly where it depends on
// E). A material is one file in fem/materials/ and one line in the registry (registry.cpp), with a
// typed, documented parameter list; a scene names it by `type` or by a `preset`.
// Equations: docs/models.md §3, §2.3.
#pragma once

#include <array>
#include <cstddef>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace mesopen::fem {

// What the kinematics give a material for each element of a batch (all arrays of length n).
struct StrainBatch {
  std::size_t n = 0;
  double dt = 0.0;               // step [s]
  const double *dxx, *dyy, *dxy; // rate of deformation D at mid-step [1/s] (D_zz = 0)
  const double *spin;            // w = (dvy/dx - dvx/dy) / 2 at mid-step [1/s]
  const double *jacobian;        // J = V / V0 at the end of the step (or its nodal average)
  const double *volume_change;   // V(n+1) - V(n) of the element [m^2]
  const double *volume_mid;      // V at mid-step [m^2]
  const double *volume0;         // initial V [m^2]
  // The deformation gradient F = dx/dX at n+1 and at n (xx, xy, yx, yy), and J^(-1/3) of each
  // (hyperelastic.hpp, inverseCubeRoots), for the materials that ask for them
  // (Material::usesDeformationGradient; null otherwise).
  std::array<const double *, 4> f{}, f_old{};
  const double *inverse_cube_root_j = nullptr, *inverse_cube_root_j_old = nullptr;
};

// Element state the material updates in place (pointers to the first element of the batch).
struct StressState {
  double *sxx, *syy, *sxy; // deviatoric stress [Pa]
  double *pressure;        // p, compression positive [Pa]
  double *energy;          // internal energy per element [J/m]
  double *plastic_strain;  // equivalent plastic strain
};

struct MaterialOutput {
  double *sound_speed;       // current sound speed sqrt((K_s + 4G/3) / rho) [m/s]
  double *shear_share;       // G / (K_s + 4G/3), in [0, 3/4] (for the stable step)
  double plastic_work = 0.0; // plastic work of this batch over the step [J/m]
};

class Material;
std::unique_ptr<Material> makeMaterial(const std::string &type_or_preset,
                                       const std::map<std::string, double> &overrides);

class Material {
public:
  virtual ~Material() = default;
  const std::string &type() const { return type_; } // the registry's name for it
  virtual double density() const = 0;               // rho0 [kg/m^3]
  virtual bool plastic() const = 0; // true when a strength model (plastic flow) is on
  virtual void update(const StrainBatch &in, StressState &state, MaterialOutput &out) const = 0;
  // True for a deviator in total form, from F (StrainBatch::f): the materials without strength.
  virtual bool usesDeformationGradient() const { return false; }
  // The equivalent plastic strain at which an element fails and is removed (erosion; an element
  // of such a material also fails when crushed to a fifth of its area); 0: never (the parameter
  // `erosion_strain` of the types that have it).
  double erosionStrain() const { return erosion_strain_; }

private:
  friend std::unique_ptr<Material> makeMaterial(const std::string &,
                                                const std::map<std::string, double> &);
  std::string type_;
  double erosion_strain_ = 0.0;
};

// A material's parameter: name, unit, meaning, allowed closed range, default.
struct ParameterInfo {
  std::string name, unit, doc;
  double lo, hi, value;
  bool boolean = false; // a switch: 1 (true) or 0 (false)
};
using Parameters = std::map<std::string, double>;

struct MaterialType {
  std::string name, doc;
  std::vector<ParameterInfo> parameters;                 // defaults: the thesis's values
  std::unique_ptr<Material> (*make)(const Parameters &); // complete, checked parameters
};

// A named parameter set of a type (thesis Tables 3.2, 3.3 and their elastic variants).
struct MaterialPreset {
  std::string name, type, doc;
  Parameters values; // overrides of the type's defaults
};

const std::vector<MaterialType> &materialTypes();
const std::vector<MaterialPreset> &materialPresets();
const MaterialType *findMaterialType(const std::string &name);
const MaterialPreset *findMaterialPreset(const std::string &name);

// The type's defaults, then the preset's values (if any), then `overrides`, checked against the
// allowed ranges. Throws std::invalid_argument naming the parameter, its value and the range.
Parameters completeParameters(const MaterialType &type, const MaterialPreset *preset,
                              const Parameters &overrides);
std::unique_ptr<Material> makeMaterial(const std::string &type_or_preset,
                                       const Parameters &overrides = {});

} // namespace mesopen::fem
