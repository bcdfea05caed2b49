// The list of material types and presets: a new material is one file in this folder and one line
// in each list below.
// Equations: docs/models.md §3.7.
#include "../material.hpp"

#include <sstream>
#include <stdexcept>

namespace mesopen::fem {

MaterialType elasticMaterialType();
MaterialType vonMisesMaterialType();
MaterialType quartzMaterialType();

const std::vector<MaterialType> &materialTypes() {
  static const std::vector<MaterialType> types{elasticMaterialType(), vonMisesMaterialType(),
                                               quartzMaterialType()};
  return types;
}

const std::vector<MaterialPreset> &materialPresets() {
  static const std::vector<MaterialPreset> presets{
      {"steel", "von-mises", "projectile steel, thesis Table 3.2, elastic-plastic", {}},
      {"steel-elastic",
       "von-mises",
       "projectile steel, thesis Table 3.2, plasticity off",
       {{"plastic", 0.0}}},
      {"quartz", "quartz", "quartz grains, thesis Table 3.3, with the overstress strength", {}},
      {"quartz-elastic",
       "quartz",
       "quartz grains, thesis Table 3.3, strength off",
       {{"strength", 0.0}}},
  };
  return presets;
}

const MaterialType *findMaterialType(const std::string &name) {
  for (const auto &t : materialTypes())
    if (t.name == name)
      return &t;
  return nullptr;
}

const MaterialPreset *findMaterialPreset(const std::string &name) {
  for (const auto &p : materialPresets())
    if (p.name == name)
      return &p;
  return nullptr;
}

Parameters completeParameters(const MaterialType &type, const MaterialPreset *preset,
                              const Parameters &overrides) {
  Parameters values;
  for (const auto &info : type.parameters)
    values[info.name] = info.value;
  auto apply = [&](const Parameters &given) {
    for (const auto &[name, value] : given) {
      const ParameterInfo *info = nullptr;
      for (const auto &p : type.parameters)
        if (p.name == name)
          info = &p;
      std::ostringstream msg;
      if (!info) {
        msg << "material type \"" << type.name << "\" has no parameter " << name << "; known:";
        for (const auto &p : type.parameters)
          msg << ' ' << p.name;
        throw std::invalid_argument(msg.str());
      }
      if (!(value >= info->lo && value <= info->hi)) {
        msg << "material parameter " << name << " = " << value
            << " is out of range; allowed: " << info->lo << " <= " << name << " <= " << info->hi
            << (info->unit.empty() ? "" : " [" + info->unit + "]");
        throw std::invalid_argument(msg.str());
      }
      values[name] = value;
    }
  };
  if (preset)
    apply(preset->values);
  apply(overrides);
  return values;
}

std::unique_ptr<Material> makeMaterial(const std::string &type_or_preset,
                                       const Parameters &overrides) {
  const MaterialPreset *preset = findMaterialPreset(type_or_preset);
  const MaterialType *type = findMaterialType(preset ? preset->type : type_or_preset);
  if (!type)
    throw std::invalid_argument("unknown material \"" + type_or_preset + "\"");
  const Parameters values = completeParameters(*type, preset, overrides);
  std::unique_ptr<Material> material = type->make(values);
  material->type_ = type->name;
  if (auto erosion = values.find("erosion_strain"); erosion != values.end())
    material->erosion_strain_ = erosion->second;
  return material;
}

} // namespace mesopen::fem
