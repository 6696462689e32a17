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
// Writing a scene back to JSON (SceneToJson).
#include "bmrScene.h"

#include <nlohmann/json.hpp>

#include <string>

namespace bmr {
namespace {
using Json = nlohmann::json;

Json
LabelsToJson(const std::vector<SceneLabel> & labels)
{
  Json out = Json::array();
  for (const auto & l : labels)
  {
    Json j = { { "name", l.name }, { "value", l.value }, { "role", LabelRoleName(l.role) } };
    if (l.role == LabelRoleEnum::Material || l.role == LabelRoleEnum::UnknownMaterial)
    {
      j["youngs_modulus_kPa"] = l.youngsModulus;
      j["poisson_ratio"] = l.poissonRatio;
    }
    if (l.role == LabelRoleEnum::UnknownMaterial)
    {
      j["bounds_kPa"] = { l.lowerBound, l.upperBound };
    }
    out.push_back(j);
  }
  return out;
}

Json
ObjectiveToJson(const std::vector<ObjectiveTerm> & objective)
{
  Json obj = Json::array();
  for (const auto & t : objective)
    obj.push_back({ { "label", t.label }, { "weight", t.weight } });
  return obj;
}

Json
LoadToJson(const SceneLoad & l)
{
  if (l.type != SceneLoad::TypeEnum::RadialDisplacement)
  {
    return { { "surface", l.surface }, { "type", "pressure" }, { "pressure_kPa", l.magnitude } };
  }
  Json load = { { "surface", l.surface },
                { "type", "radial_displacement" },
                { "center_mm", l.center },
                { "magnitude_mm", l.magnitude } };
  if (l.axis != std::array<double, 3>{ { 0, 0, 0 } })
  {
    load["axis"] = l.axis;
  }
  if (l.semiAxes != std::array<double, 3>{ { 0, 0, 0 } })
  {
    load["semi_axes_mm"] = l.semiAxes;
  }
  return load;
}

Json
LoadsToJson(const std::vector<SceneLoad> & loads)
{
  Json out = Json::array();
  for (const auto & l : loads)
  {
    out.push_back(LoadToJson(l));
  }
  return out;
}

Json
RegionOfInterestToJson(const Scene & scene)
{
  Json roi = { { "boundary", scene.roiBoundaryFixed ? "fixed" : "free" } };
  if (scene.roiMargin >= 0.0)
    roi["margin_mm"] = scene.roiMargin;
  return roi;
}

// Labels are written by name; a value the scene does not describe is written as its number.
std::string
LabelNameOrValue(const Scene & scene, std::int32_t value)
{
  const SceneLabel * l = scene.FindLabelValue(value);
  return l ? l->name : std::to_string(value);
}

// Adds the non-empty per-label sizes (mesh.KEY) to \a mesh.
void
SizesPerLabelToJson(const Scene & scene, Json & mesh)
{
  for (const auto & keyAndSizes : scene.mesh.SizesPerLabel())
  {
    if (!keyAndSizes.second->empty())
    {
      Json per = Json::object();
      for (const auto & kv : *keyAndSizes.second)
      {
        per[LabelNameOrValue(scene, kv.first)] = kv.second;
      }
      mesh[keyAndSizes.first] = per;
    }
  }
}

Json
MeshToJson(const Scene & scene)
{
  const MeshingParameters & m = scene.mesh;

  Json mesh = { { "cell_size_mm", m.cellSize },
                { "facet_size_mm", m.facetSize },
                { "facet_distance_mm", m.facetDistance },
                { "facet_angle_deg", m.facetAngle },
                { "cell_radius_edge_ratio", m.cellRadiusEdgeRatio },
                { "optimize", m.optimize },
                { "exude", m.exude },
                { "sliver_bound_deg", m.sliverBound },
                { "minimum_dihedral_angle_deg", m.minimumDihedralAngle },
                { "random_seed", m.randomSeed },
                { "label_surfaces",
                  m.labelSurfaces == MeshingParameters::LabelSurfaces::Distance ? "distance" : "voxels" } };
  SizesPerLabelToJson(scene, mesh);
  if (m.Refines())
  {
    Json names = Json::array();
    for (std::int32_t value : m.refineNearLabels)
    {
      names.push_back(LabelNameOrValue(scene, value));
    }
    mesh["refine_near"] = { { "labels", names }, { "distance_mm", m.refineDistance }, { "size_mm", m.refineSize } };
  }
  return mesh;
}
} // namespace

std::string
SceneToJson(const Scene & scene)
{
  Json root;
  root["units"] = { { "length", "mm" }, { "modulus", "kPa" }, { "force", "mN" } };
  root["labels"] = LabelsToJson(scene.labels);
  if (!scene.gauge.empty())
    root["gauge"] = scene.gauge;
  root["formulation"] =
    scene.formulation == ElementFormulationEnum::NodalAveragedPressure ? "nodal_averaged_pressure" : "standard";
  root["model"] = scene.model == MaterialModelEnum::NeoHookean ? "neo_hookean" : "linear";
  if (!scene.forceSurfaces.empty())
    root["force_surfaces"] = scene.forceSurfaces;
  if (!scene.objective.empty())
    root["objective"] = ObjectiveToJson(scene.objective);
  if (!scene.loads.empty())
    root["loads"] = LoadsToJson(scene.loads);
  if (!scene.movingLandmarks.empty() || !scene.fixedLandmarks.empty())
  {
    root["landmarks"] = { { "moving", scene.movingLandmarks }, { "fixed", scene.fixedLandmarks } };
  }
  if (scene.roiMargin >= 0.0 || scene.roiBoundaryFixed)
    root["region_of_interest"] = RegionOfInterestToJson(scene);
  root["mesh"] = MeshToJson(scene);
  return root.dump(2) + "\n";
}

} // namespace bmr
