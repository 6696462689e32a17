/*=========================================================================
 *
 *  Copyright NumFOCUS
 *
 *  Licensed under the Apache License, Version 2.0 (the "License");
 *  you may not use this file except in compliance with the License.
 *  You may obtain a copy of the License at
 *
 *         http://www.apache.org/licenses/LICENSE-2.0.txt
 *
 *  Unless required by applicable law or agreed to in writing, software
 *  distributed under the License is distributed on an "AS IS" BASIS,
 *  WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
 *  See the License for the specific language governing permissions and
 *  limitations under the License.
 *
 *=========================================================================*/
// The scene's queries and validation, label lists (ParseLabelList) and the stream operators of its enums.
#include "bmrScene.h"

#include "bmrError.h"
#include "bmrSceneInternal.h"

#include <algorithm>
#include <ostream>
#include <sstream>

namespace bmr {
using detail::SceneError;

const char *
LabelRoleName(LabelRoleEnum role)
{
  switch (role)
  {
    case LabelRoleEnum::Material:
      return "material";
    case LabelRoleEnum::UnknownMaterial:
      return "unknown_material";
    case LabelRoleEnum::Fixed:
      return "fixed";
    case LabelRoleEnum::Hollow:
      return "hollow";
    case LabelRoleEnum::Outside:
      return "outside";
  }
  return "?";
}

std::vector<const SceneLabel *>
Scene::UnknownLabels() const
{
  std::vector<const SceneLabel *> unknown;
  for (const SceneLabel & l : labels)
  {
    if (l.role == LabelRoleEnum::UnknownMaterial)
    {
      unknown.push_back(&l);
    }
  }
  return unknown;
}

const SceneLabel *
Scene::GaugeLabel() const
{
  if (!gauge.empty())
  {
    return FindLabel(gauge);
  }
  for (const SceneLabel & l : labels)
  {
    if (l.role == LabelRoleEnum::Material)
    {
      return &l;
    }
  }
  return nullptr;
}

const SceneLabel *
Scene::FindLabel(const std::string & labelName) const
{
  for (const auto & l : labels)
  {
    if (l.name == labelName)
    {
      return &l;
    }
  }
  return nullptr;
}

const SceneLabel *
Scene::FindLabelValue(std::int32_t value) const
{
  for (const auto & l : labels)
  {
    if (l.value == value)
    {
      return &l;
    }
  }
  return nullptr;
}

std::vector<std::int32_t>
Scene::ExcludedLabels() const
{
  std::vector<std::int32_t> v;
  for (const auto & l : labels)
  {
    if (l.role == LabelRoleEnum::Fixed || l.role == LabelRoleEnum::Hollow || l.role == LabelRoleEnum::Outside)
    {
      v.push_back(l.value);
    }
  }
  return v;
}

std::vector<std::int32_t>
Scene::OutsideLabels() const
{
  std::vector<std::int32_t> v;
  for (const auto & l : labels)
  {
    if (l.role == LabelRoleEnum::Outside)
    {
      v.push_back(l.value);
    }
  }
  return v;
}

std::vector<std::string>
Scene::Warnings() const
{
  std::vector<std::string> warnings;
  if (formulation == ElementFormulationEnum::NodalAveragedPressure)
  {
    return warnings;
  }
  const char * remedy = model == MaterialModelEnum::NeoHookean
                          ? "the neo-Hookean model has no locking-free formulation: lower nu or use \"model\": "
                            "\"linear\" with \"formulation\": \"nodal_averaged_pressure\""
                          : "set \"formulation\": \"nodal_averaged_pressure\" in the scene";
  for (const SceneLabel & l : labels)
  {
    if ((l.role == LabelRoleEnum::Material || l.role == LabelRoleEnum::UnknownMaterial) && l.poissonRatio > 0.45)
    {
      std::ostringstream os;
      os << "label \"" << l.name << "\" has nu = " << l.poissonRatio
         << " > 0.45: linear tetrahedra lock (too stiff) near incompressibility; " << remedy;
      warnings.push_back(os.str());
    }
  }
  return warnings;
}

std::string
VoxelLimitReason(double coarsestVoxel, double limit)
{
  std::ostringstream os;
  os << "label voxels of up to " << coarsestVoxel << " mm: the modulus is reported as not determined, because the "
     << "rescans' interval is stated only from voxels of at most " << limit << " mm (its coverage was shown at 1 mm; "
     << "at 2-3 mm slices it missed the truth)";
  return os.str();
}

std::vector<std::string>
Scene::EstimationWarnings(double finestVoxel) const
{
  std::vector<std::string> warnings;
  if (std::none_of(
        labels.begin(), labels.end(), [](const SceneLabel & l) { return l.role == LabelRoleEnum::UnknownMaterial; }))
  {
    return warnings;
  }
  if (mesh.facetDistance > 0.5 * finestVoxel)
  {
    std::ostringstream os;
    os << "mesh.facet_distance_mm = " << mesh.facetDistance << " exceeds half the finest label voxel ("
       << 0.5 * finestVoxel
       << " mm): the mesh's organ surfaces may leave the labels' by more than the shape changes that carry the "
          "modulus, which is then unreliable (the registration itself is not affected)";
    warnings.push_back(os.str());
  }
  return warnings;
}

namespace {
// Checks each label on its own and that something is simulated; returns whether a label has the role fixed
// (which holds the model against rigid-body motion).
bool
CheckSceneLabels(const std::vector<SceneLabel> & labels, const std::string & src)
{
  bool                   simulated = false, fixedLabel = false;
  std::set<std::string>  names;
  std::set<std::int32_t> values;
  for (const auto & l : labels)
  {
    const std::string entry = "labels[" + l.name + "]";
    if (l.name.empty())
    {
      SceneError(src, "labels", "every label needs a name");
    }
    if (!names.insert(l.name).second)
    {
      SceneError(src, entry, "the name is used twice");
    }
    if (!values.insert(l.value).second)
    {
      SceneError(src, entry + ".value", "label value " + std::to_string(l.value) + " is used twice");
    }
    if (l.role == LabelRoleEnum::Material || l.role == LabelRoleEnum::UnknownMaterial)
    {
      simulated = true;
      if (l.value == 0)
      {
        SceneError(src, entry + ".value", "label 0 is the background and cannot be a material");
      }
      if (!(l.youngsModulus > 0.0))
      {
        SceneError(src, entry + ".youngs_modulus_kPa", "must be > 0, got " + std::to_string(l.youngsModulus));
      }
      if (!(l.poissonRatio < 0.5 && l.poissonRatio > -1.0))
      {
        SceneError(src,
                   entry + ".poisson_ratio",
                   "must lie in (-1, 0.5) for a compressible linear-elastic solid, got " +
                     std::to_string(l.poissonRatio));
      }
    }
    if (l.role == LabelRoleEnum::UnknownMaterial &&
        !(l.lowerBound > 0.0 && l.lowerBound <= l.youngsModulus && l.youngsModulus <= l.upperBound))
    {
      SceneError(src, entry + ".bounds_kPa", "must satisfy 0 < lower <= youngs_modulus_kPa <= upper");
    }
    fixedLabel = fixedLabel || l.role == LabelRoleEnum::Fixed;
  }
  if (!simulated)
  {
    SceneError(src, "labels", "no label has the role material or unknown_material: there is nothing to simulate");
  }
  return fixedLabel;
}

void
CheckLoadSurface(const Scene & scene, const std::string & src, const std::string & surface, const std::string & entry)
{
  const SceneLabel * l = scene.FindLabel(surface);
  if (!l)
  {
    SceneError(src, entry, "\"" + surface + "\" is not a label of the scene");
  }
  if (l->role != LabelRoleEnum::Hollow && l->role != LabelRoleEnum::Outside && l->role != LabelRoleEnum::Fixed)
  {
    SceneError(
      src, entry, "\"" + surface + "\" must be a hollow, fixed or outside label (its wall is a mesh boundary)");
  }
}

// Checks the surfaces of force_surfaces and loads; returns whether a load prescribes a displacement
// (which holds the model against rigid-body motion).
bool
CheckForceSurfacesAndLoads(const Scene & scene, const std::string & src)
{
  for (std::size_t i = 0; i < scene.forceSurfaces.size(); ++i)
  {
    CheckLoadSurface(scene, src, scene.forceSurfaces[i], "force_surfaces[" + std::to_string(i) + "]");
  }
  bool displacementLoad = false;
  for (std::size_t i = 0; i < scene.loads.size(); ++i)
  {
    const std::string entry = "loads[" + std::to_string(i) + "]";
    CheckLoadSurface(scene, src, scene.loads[i].surface, entry + ".surface");
    displacementLoad = displacementLoad || scene.loads[i].type == SceneLoad::TypeEnum::RadialDisplacement;
  }
  return displacementLoad;
}

void
CheckObjective(const Scene & scene, const std::string & src)
{
  for (std::size_t i = 0; i < scene.objective.size(); ++i)
  {
    const std::string entry = "objective[" + std::to_string(i) + "]";
    if (!scene.FindLabel(scene.objective[i].label))
    {
      SceneError(src, entry + ".label", "\"" + scene.objective[i].label + "\" is not a label of the scene");
    }
    if (!(scene.objective[i].weight > 0.0))
    {
      SceneError(src, entry + ".weight", "must be > 0");
    }
  }
}

void
CheckMeshingParameters(const MeshingParameters & m, const std::string & src)
{
  const std::pair<const char *, double> sizes[] = { { "cell_size_mm", m.cellSize },
                                                    { "facet_size_mm", m.facetSize },
                                                    { "facet_distance_mm", m.facetDistance } };
  for (const auto & s : sizes)
  {
    if (!(s.second > 0.0))
    {
      SceneError(src, std::string("mesh.") + s.first, "must be > 0");
    }
  }
  for (const auto & keyAndMap : m.SizesPerLabel())
  {
    for (const auto & kv : *keyAndMap.second)
    {
      if (!(kv.second > 0.0))
      {
        SceneError(src, std::string("mesh.") + keyAndMap.first, "sizes must be > 0");
      }
    }
  }
  if (!(m.sliverBound > 0.0 && m.sliverBound < 60.0))
  {
    SceneError(src, "mesh.sliver_bound_deg", "must lie in (0, 60) degrees");
  }
  if (!(m.refineDistance >= 0.0) || !(m.refineSize >= 0.0) || (m.Refines() && !(m.refineSize > 0.0)))
  {
    SceneError(src, "mesh.refine_near", "distance_mm and size_mm must be >= 0");
  }
  if (!(m.minimumDihedralAngle >= 0.0 && m.minimumDihedralAngle < 70.0))
  {
    SceneError(src, "mesh.minimum_dihedral_angle_deg", "must lie in [0, 70) degrees");
  }
}
} // namespace

void
Scene::Validate() const
{
  const std::string src = name.empty() ? std::string("scene") : name;
  const bool        fixedLabel = CheckSceneLabels(labels, src);
  if (!gauge.empty())
  {
    const SceneLabel * g = FindLabel(gauge);
    if (!g || g->role != LabelRoleEnum::Material)
    {
      SceneError(src, "gauge", "\"" + gauge + "\" must name a label with the role material (known modulus)");
    }
  }
  const bool displacementLoad = CheckForceSurfacesAndLoads(*this, src);
  CheckObjective(*this, src);
  // In an estimation (FEMElasticityOptimizer) the walls of the force surfaces are displacement-controlled,
  // which holds the model too.
  const bool estimatedWalls = !forceSurfaces.empty() && !objective.empty();
  if (!fixedLabel && !roiBoundaryFixed && !displacementLoad && !estimatedWalls)
  {
    SceneError(src,
               "labels",
               "nothing prevents rigid-body motion: give a label the role fixed, set region_of_interest.boundary to "
               "\"fixed\", prescribe a displacement load, or estimate the loads of force_surfaces");
  }
  CheckMeshingParameters(mesh, src);
  if (model == MaterialModelEnum::NeoHookean && formulation == ElementFormulationEnum::NodalAveragedPressure)
  {
    SceneError(src, "model", "the neo-Hookean model has only the standard P1 formulation, not nodal_averaged_pressure");
  }
}

std::ostream &
operator<<(std::ostream & os, MaterialModelEnum value)
{
  switch (value)
  {
    case MaterialModelEnum::Linear:
      return os << "bmr::MaterialModelEnum::Linear";
    case MaterialModelEnum::NeoHookean:
      return os << "bmr::MaterialModelEnum::NeoHookean";
  }
  return os << "INVALID VALUE FOR bmr::MaterialModelEnum";
}

void
Scene::ValidateAgainstLabels(const std::set<std::int32_t> & present, const std::string & what) const
{
  const std::string src = name.empty() ? std::string("scene") : name;
  for (std::int32_t v : present)
  {
    if (v != 0 && !FindLabelValue(v))
    {
      SceneError(src, "labels", what + " contains label " + std::to_string(v) + ", which the scene does not describe");
    }
  }
  auto requirePresent = [&](const std::string & labelName, const std::string & entry) {
    const SceneLabel * l = FindLabel(labelName);
    if (l && present.count(l->value) == 0)
    {
      SceneError(
        src, entry, "label \"" + labelName + "\" (value " + std::to_string(l->value) + ") is absent from " + what);
    }
  };
  for (const auto & l : labels)
  {
    if (l.role == LabelRoleEnum::Material || l.role == LabelRoleEnum::UnknownMaterial)
    {
      requirePresent(l.name, "labels[" + l.name + "]");
    }
  }
  for (std::size_t i = 0; i < forceSurfaces.size(); ++i)
  {
    requirePresent(forceSurfaces[i], "force_surfaces[" + std::to_string(i) + "]");
  }
  for (std::size_t i = 0; i < loads.size(); ++i)
  {
    if (FindLabel(loads[i].surface)->value != 0)
    {
      requirePresent(loads[i].surface, "loads[" + std::to_string(i) + "].surface");
    }
  }
  for (std::size_t i = 0; i < objective.size(); ++i)
  {
    requirePresent(objective[i].label, "objective[" + std::to_string(i) + "].label");
  }
}


std::vector<std::int32_t>
ParseLabelList(const std::string & text, const Scene * scene)
{
  std::vector<std::int32_t> labels;
  if (text == "none")
  {
    return labels;
  }
  std::istringstream in(text);
  std::string        item;
  while (std::getline(in, item, ','))
  {
    if (item.empty())
    {
      continue;
    }
    const SceneLabel * named = scene ? scene->FindLabel(item) : nullptr;
    if (named)
    {
      labels.push_back(named->value);
      continue;
    }
    char *     end = nullptr;
    const long v = std::strtol(item.c_str(), &end, 10);
    if (end == item.c_str() || *end != '\0')
    {
      FailInput("ParseLabelList", "label \"" + item + "\" is neither an integer nor a label of the scene");
    }
    labels.push_back(static_cast<std::int32_t>(v));
  }
  return labels;
}

std::ostream &
operator<<(std::ostream & os, LabelRoleEnum value)
{
  return os << "bmr::LabelRoleEnum::" << LabelRoleName(value);
}

std::ostream &
operator<<(std::ostream & os, SceneLoad::TypeEnum value)
{
  switch (value)
  {
    case SceneLoad::TypeEnum::RadialDisplacement:
      return os << "bmr::SceneLoad::TypeEnum::RadialDisplacement";
    case SceneLoad::TypeEnum::Pressure:
      return os << "bmr::SceneLoad::TypeEnum::Pressure";
  }
  return os << "INVALID VALUE FOR bmr::SceneLoad::TypeEnum";
}

} // namespace bmr
