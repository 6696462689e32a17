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
// Reading a scene from JSON (ParseScene, ReadScene): the checks of each key as it is parsed.
#include "bmrScene.h"

#include "bmrError.h"
#include "bmrSceneInternal.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <sstream>

namespace bmr {
using detail::SceneError;

namespace {
using Json = nlohmann::json;

void
CheckKeys(const Json &                  object,
          const std::set<std::string> & allowed,
          const std::string &           source,
          const std::string &           entry)
{
  if (!object.is_object())
  {
    SceneError(source, entry, "must be a JSON object");
  }
  for (auto it = object.begin(); it != object.end(); ++it)
  {
    if (allowed.count(it.key()) == 0)
    {
      SceneError(source, entry + "." + it.key(), "unknown key");
    }
  }
}

double
GetNumber(const Json & object, const std::string & key, const std::string & source, const std::string & entry)
{
  const Json & v = object.at(key);
  if (!v.is_number())
  {
    SceneError(source, entry + "." + key, "must be a number");
  }
  const double d = v.get<double>();
  if (!std::isfinite(d))
  {
    SceneError(source, entry + "." + key, "must be finite");
  }
  return d;
}

std::string
GetString(const Json & object, const std::string & key, const std::string & source, const std::string & entry)
{
  const Json & v = object.at(key);
  if (!v.is_string())
  {
    SceneError(source, entry + "." + key, "must be a string");
  }
  return v.get<std::string>();
}

bool
GetBool(const Json & object, const std::string & key, const std::string & source, const std::string & entry)
{
  const Json & v = object.at(key);
  if (!v.is_boolean())
  {
    SceneError(source, entry + "." + key, "must be true or false");
  }
  return v.get<bool>();
}

std::array<double, 3>
GetPoint(const Json & object, const std::string & key, const std::string & source, const std::string & entry)
{
  const Json & v = object.at(key);
  if (!v.is_array() || v.size() != 3)
  {
    SceneError(source, entry + "." + key, "must be an array of 3 numbers [mm]");
  }
  std::array<double, 3> p;
  for (int i = 0; i < 3; ++i)
  {
    if (!v[i].is_number() || !std::isfinite(v[i].get<double>()))
    {
      SceneError(source, entry + "." + key, "must be an array of 3 finite numbers [mm]");
    }
    p[i] = v[i].get<double>();
  }
  return p;
}

LabelRoleEnum
ParseRole(const std::string & s, const std::string & source, const std::string & entry)
{
  if (s == "material")
    return LabelRoleEnum::Material;
  if (s == "unknown_material")
    return LabelRoleEnum::UnknownMaterial;
  if (s == "fixed")
    return LabelRoleEnum::Fixed;
  if (s == "hollow")
    return LabelRoleEnum::Hollow;
  if (s == "outside")
    return LabelRoleEnum::Outside;
  SceneError(source, entry + ".role", "\"" + s + "\" is not one of material, unknown_material, fixed, hollow, outside");
}

void
CheckUnits(const Json & u, const std::string & source)
{
  CheckKeys(u, { "length", "modulus", "force" }, source, "units");
  const std::pair<const char *, const char *> expected[] = { { "length", "mm" },
                                                             { "modulus", "kPa" },
                                                             { "force", "mN" } };
  for (const auto & e : expected)
  {
    if (u.contains(e.first) && GetString(u, e.first, source, "units") != e.second)
    {
      SceneError(source, std::string("units.") + e.first, std::string("only \"") + e.second + "\" is supported");
    }
  }
}

SceneLabel
ParseLabel(const Json & j, const std::string & source, const std::string & entry)
{
  CheckKeys(j, { "name", "value", "role", "youngs_modulus_kPa", "poisson_ratio", "bounds_kPa" }, source, entry);
  SceneLabel l;
  if (!j.contains("name") || !j.contains("value") || !j.contains("role"))
  {
    SceneError(source, entry, "needs name, value and role");
  }
  l.name = GetString(j, "name", source, entry);
  if (!j["value"].is_number_integer())
  {
    SceneError(source, entry + ".value", "must be an integer label value");
  }
  l.value = j["value"].get<std::int32_t>();
  l.role = ParseRole(GetString(j, "role", source, entry), source, entry);
  const bool simulated = l.role == LabelRoleEnum::Material || l.role == LabelRoleEnum::UnknownMaterial;
  if (simulated)
  {
    if (!j.contains("youngs_modulus_kPa") || !j.contains("poisson_ratio"))
    {
      SceneError(source, "labels[" + l.name + "]", "a material needs youngs_modulus_kPa and poisson_ratio");
    }
    l.youngsModulus = GetNumber(j, "youngs_modulus_kPa", source, "labels[" + l.name + "]");
    l.poissonRatio = GetNumber(j, "poisson_ratio", source, "labels[" + l.name + "]");
  }
  else if (j.contains("youngs_modulus_kPa") || j.contains("poisson_ratio"))
  {
    SceneError(source, "labels[" + l.name + "]", "only material labels take youngs_modulus_kPa / poisson_ratio");
  }
  if (j.contains("bounds_kPa"))
  {
    if (l.role != LabelRoleEnum::UnknownMaterial)
    {
      SceneError(source, "labels[" + l.name + "].bounds_kPa", "only an unknown_material takes bounds");
    }
    const Json & b = j["bounds_kPa"];
    if (!b.is_array() || b.size() != 2 || !b[0].is_number() || !b[1].is_number())
    {
      SceneError(source, "labels[" + l.name + "].bounds_kPa", "must be [lower, upper] in kPa");
    }
    l.lowerBound = b[0].get<double>();
    l.upperBound = b[1].get<double>();
  }
  else if (l.role == LabelRoleEnum::UnknownMaterial)
  {
    SceneError(source, "labels[" + l.name + "]", "an unknown_material needs bounds_kPa");
  }
  return l;
}

void
ParseGaugeFormulationAndModel(const Json & root, const std::string & source, Scene & scene)
{
  if (root.contains("gauge"))
  {
    scene.gauge = GetString(root, "gauge", source, "scene");
  }
  if (root.contains("formulation"))
  {
    const std::string f = GetString(root, "formulation", source, "scene");
    if (f != "standard" && f != "nodal_averaged_pressure")
    {
      SceneError(source, "formulation", "\"" + f + "\" is not standard or nodal_averaged_pressure");
    }
    scene.formulation =
      f == "nodal_averaged_pressure" ? ElementFormulationEnum::NodalAveragedPressure : ElementFormulationEnum::Standard;
  }
  if (root.contains("model"))
  {
    const std::string m = GetString(root, "model", source, "scene");
    if (m != "linear" && m != "neo_hookean")
    {
      SceneError(source, "model", "\"" + m + "\" is not linear or neo_hookean");
    }
    scene.model = m == "neo_hookean" ? MaterialModelEnum::NeoHookean : MaterialModelEnum::Linear;
  }
}

// Appends the label names of the optional array root[key] to out.
void
ParseLabelNameList(const Json & root, const char * key, const std::string & source, std::vector<std::string> & out)
{
  if (!root.contains(key))
  {
    return;
  }
  if (!root[key].is_array())
  {
    SceneError(source, key, "must be an array of label names");
  }
  for (const auto & v : root[key])
  {
    if (!v.is_string())
    {
      SceneError(source, key, "must be an array of label names");
    }
    out.push_back(v.get<std::string>());
  }
}

void
ParseObjective(const Json & objective, const std::string & source, std::vector<ObjectiveTerm> & out)
{
  if (!objective.is_array())
  {
    SceneError(source, "objective", "must be an array of {label, weight}");
  }
  for (std::size_t i = 0; i < objective.size(); ++i)
  {
    const Json &      j = objective[i];
    const std::string entry = "objective[" + std::to_string(i) + "]";
    CheckKeys(j, { "label", "weight" }, source, entry);
    ObjectiveTerm t;
    if (!j.contains("label"))
    {
      SceneError(source, entry, "needs a label");
    }
    t.label = GetString(j, "label", source, entry);
    if (j.contains("weight"))
    {
      t.weight = GetNumber(j, "weight", source, entry);
    }
    out.push_back(t);
  }
}

// The keys of a radial_displacement load: center, magnitude and the optional axis or semi-axes.
void
ParseRadialDisplacement(const Json & j, const std::string & source, const std::string & entry, SceneLoad & load)
{
  if (!j.contains("center_mm") || !j.contains("magnitude_mm"))
  {
    SceneError(source, entry, "a radial_displacement needs center_mm and magnitude_mm");
  }
  load.center = GetPoint(j, "center_mm", source, entry);
  load.magnitude = GetNumber(j, "magnitude_mm", source, entry);
  if (j.contains("axis"))
  {
    load.axis = GetPoint(j, "axis", source, entry);
    const double norm =
      std::sqrt(load.axis[0] * load.axis[0] + load.axis[1] * load.axis[1] + load.axis[2] * load.axis[2]);
    if (!(norm > 0.0) || !std::isfinite(norm))
    {
      SceneError(source, entry + ".axis", "must be a non-zero direction [x, y, z]");
    }
    for (double & a : load.axis)
    {
      a /= norm;
    }
  }
  if (j.contains("semi_axes_mm"))
  {
    if (j.contains("axis"))
    {
      SceneError(source, entry, "give either axis or semi_axes_mm, not both");
    }
    load.semiAxes = GetPoint(j, "semi_axes_mm", source, entry);
    for (double a : load.semiAxes)
    {
      if (!(a > 0.0) || !std::isfinite(a))
      {
        SceneError(source, entry + ".semi_axes_mm", "must be three positive lengths [mm]");
      }
    }
  }
}

SceneLoad
ParseLoad(const Json & j, const std::string & source, const std::string & entry)
{
  CheckKeys(
    j, { "surface", "type", "center_mm", "axis", "semi_axes_mm", "magnitude_mm", "pressure_kPa" }, source, entry);
  SceneLoad load;
  if (!j.contains("surface") || !j.contains("type"))
  {
    SceneError(source, entry, "needs surface and type");
  }
  load.surface = GetString(j, "surface", source, entry);
  const std::string type = GetString(j, "type", source, entry);
  if (type == "radial_displacement")
  {
    load.type = SceneLoad::TypeEnum::RadialDisplacement;
    ParseRadialDisplacement(j, source, entry, load);
  }
  else if (type == "pressure")
  {
    load.type = SceneLoad::TypeEnum::Pressure;
    if (!j.contains("pressure_kPa"))
    {
      SceneError(source, entry, "a pressure load needs pressure_kPa");
    }
    load.magnitude = GetNumber(j, "pressure_kPa", source, entry);
  }
  else
  {
    SceneError(source, entry + ".type", "\"" + type + "\" is not radial_displacement or pressure");
  }
  return load;
}

void
ParseLoads(const Json & loads, const std::string & source, std::vector<SceneLoad> & out)
{
  if (!loads.is_array())
  {
    SceneError(source, "loads", "must be an array of load objects");
  }
  for (std::size_t i = 0; i < loads.size(); ++i)
  {
    out.push_back(ParseLoad(loads[i], source, "loads[" + std::to_string(i) + "]"));
  }
}

void
ParseLandmarks(const Json & j, const std::string & source, Scene & scene)
{
  CheckKeys(j, { "moving", "fixed" }, source, "landmarks");
  if (j.contains("moving"))
    scene.movingLandmarks = GetString(j, "moving", source, "landmarks");
  if (j.contains("fixed"))
    scene.fixedLandmarks = GetString(j, "fixed", source, "landmarks");
}

void
ParseRegionOfInterest(const Json & j, const std::string & source, Scene & scene)
{
  CheckKeys(j, { "margin_mm", "boundary" }, source, "region_of_interest");
  if (j.contains("margin_mm"))
  {
    scene.roiMargin = GetNumber(j, "margin_mm", source, "region_of_interest");
    if (scene.roiMargin < 0.0)
    {
      SceneError(source, "region_of_interest.margin_mm", "must be >= 0");
    }
  }
  if (j.contains("boundary"))
  {
    const std::string b = GetString(j, "boundary", source, "region_of_interest");
    if (b != "free" && b != "fixed")
    {
      SceneError(source, "region_of_interest.boundary", "must be \"free\" or \"fixed\"");
    }
    scene.roiBoundaryFixed = b == "fixed";
  }
}

// All mesh keys but the values of the per-label sizes (MeshingParameters::SizesPerLabel), which need the labels
// (ParseSizesPerLabel).
void
ParseMeshingParameters(const Json & j, const std::string & source, MeshingParameters & m)
{
  CheckKeys(j,
            { "cell_size_mm",
              "facet_size_mm",
              "facet_distance_mm",
              "facet_angle_deg",
              "cell_radius_edge_ratio",
              "cell_size_per_label_mm",
              "facet_size_per_label_mm",
              "facet_distance_per_label_mm",
              "optimize",
              "exude",
              "sliver_bound_deg",
              "random_seed",
              "minimum_dihedral_angle_deg",
              "label_surfaces",
              "refine_near" },
            source,
            "mesh");
  if (j.contains("cell_size_mm"))
    m.cellSize = GetNumber(j, "cell_size_mm", source, "mesh");
  if (j.contains("facet_size_mm"))
    m.facetSize = GetNumber(j, "facet_size_mm", source, "mesh");
  if (j.contains("facet_distance_mm"))
    m.facetDistance = GetNumber(j, "facet_distance_mm", source, "mesh");
  if (j.contains("facet_angle_deg"))
    m.facetAngle = GetNumber(j, "facet_angle_deg", source, "mesh");
  if (j.contains("cell_radius_edge_ratio"))
    m.cellRadiusEdgeRatio = GetNumber(j, "cell_radius_edge_ratio", source, "mesh");
  if (j.contains("optimize"))
    m.optimize = GetBool(j, "optimize", source, "mesh");
  if (j.contains("exude"))
    m.exude = GetBool(j, "exude", source, "mesh");
  if (j.contains("sliver_bound_deg"))
    m.sliverBound = GetNumber(j, "sliver_bound_deg", source, "mesh");
  if (j.contains("minimum_dihedral_angle_deg"))
    m.minimumDihedralAngle = GetNumber(j, "minimum_dihedral_angle_deg", source, "mesh");
  if (j.contains("label_surfaces"))
  {
    const std::string surfaces = GetString(j, "label_surfaces", source, "mesh");
    if (surfaces != "voxels" && surfaces != "distance")
    {
      SceneError(source, "mesh.label_surfaces", "must be \"voxels\" or \"distance\", got \"" + surfaces + "\"");
    }
    m.labelSurfaces =
      surfaces == "distance" ? MeshingParameters::LabelSurfaces::Distance : MeshingParameters::LabelSurfaces::Voxels;
  }
  if (j.contains("random_seed"))
  {
    if (!j["random_seed"].is_number_unsigned())
    {
      SceneError(source, "mesh.random_seed", "must be a non-negative integer");
    }
    m.randomSeed = j["random_seed"].get<unsigned int>();
  }
  for (const auto & keyAndSizes : m.SizesPerLabel())
  {
    if (j.contains(keyAndSizes.first) && !j[keyAndSizes.first].is_object())
    {
      SceneError(source, std::string("mesh.") + keyAndSizes.first, "must be an object {label name: size in mm}");
    }
  }
}

// "refine_near": {"labels": [names], "distance_mm": d, "size_mm": s} (MeshingParameters::refineNearLabels).
void
ParseRefineNear(const Json & j, const std::string & source, Scene & scene)
{
  if (!j.is_object())
  {
    SceneError(source, "mesh.refine_near", "must be an object {labels, distance_mm, size_mm}");
  }
  CheckKeys(j, { "labels", "distance_mm", "size_mm" }, source, "mesh.refine_near");
  if (!j.contains("labels") || !j["labels"].is_array() || j["labels"].empty())
  {
    SceneError(source, "mesh.refine_near.labels", "must be a non-empty list of label names");
  }
  for (const Json & name : j["labels"])
  {
    const SceneLabel * l = name.is_string() ? scene.FindLabel(name.get<std::string>()) : nullptr;
    if (!l)
    {
      SceneError(source, "mesh.refine_near.labels", "holds " + name.dump() + ", which is not a label of the scene");
    }
    scene.mesh.refineNearLabels.push_back(l->value);
  }
  scene.mesh.refineDistance = GetNumber(j, "distance_mm", source, "mesh.refine_near");
  scene.mesh.refineSize = GetNumber(j, "size_mm", source, "mesh.refine_near");
}

// Per-label sizes (mesh.KEY) refer to label names, resolved once the labels are known; \a sizes receives them.
void
ParseSizesPerLabel(const Json &                     perLabel,
                   const std::string &              key,
                   const std::string &              source,
                   const Scene &                    scene,
                   std::map<std::int32_t, double> & sizes)
{
  for (auto it = perLabel.begin(); it != perLabel.end(); ++it)
  {
    const SceneLabel * l = scene.FindLabel(it.key());
    if (!l)
    {
      SceneError(source, "mesh." + key + "." + it.key(), "is not a label of the scene");
    }
    if (!it.value().is_number())
    {
      SceneError(source, "mesh." + key + "." + it.key(), "must be a number [mm]");
    }
    sizes[l->value] = it.value().get<double>();
  }
}

// The scene's "mesh" object, parsed after the labels, to which its per-label sizes and refine_near refer.
void
ParseMesh(const Json & mesh, const std::string & source, Scene & scene)
{
  ParseMeshingParameters(mesh, source, scene.mesh);
  for (const auto & keyAndSizes : scene.mesh.SizesPerLabel())
  {
    if (mesh.contains(keyAndSizes.first))
    {
      ParseSizesPerLabel(mesh[keyAndSizes.first], keyAndSizes.first, source, scene, *keyAndSizes.second);
    }
  }
  if (mesh.contains("refine_near"))
  {
    ParseRefineNear(mesh["refine_near"], source, scene);
  }
}
} // namespace

Scene
ParseScene(const std::string & text, const std::string & source)
{
  Json root;
  try
  {
    root = Json::parse(text);
  }
  catch (const std::exception & e)
  {
    SceneError(source, "JSON", e.what());
  }
  Scene scene;
  scene.name = source;
  CheckKeys(root,
            { "name",
              "units",
              "labels",
              "gauge",
              "force_surfaces",
              "objective",
              "loads",
              "landmarks",
              "region_of_interest",
              "mesh",
              "formulation",
              "model" },
            source,
            "scene");
  if (root.contains("name"))
  {
    GetString(root, "name", source, "scene");
  }
  if (root.contains("units"))
  {
    CheckUnits(root["units"], source);
  }
  if (!root.contains("labels") || !root["labels"].is_array() || root["labels"].empty())
  {
    SceneError(source, "labels", "must be a non-empty array of label objects");
  }
  for (std::size_t i = 0; i < root["labels"].size(); ++i)
  {
    scene.labels.push_back(ParseLabel(root["labels"][i], source, "labels[" + std::to_string(i) + "]"));
  }
  ParseGaugeFormulationAndModel(root, source, scene);
  ParseLabelNameList(root, "force_surfaces", source, scene.forceSurfaces);
  if (root.contains("objective"))
  {
    ParseObjective(root["objective"], source, scene.objective);
  }
  if (root.contains("loads"))
  {
    ParseLoads(root["loads"], source, scene.loads);
  }
  if (root.contains("landmarks"))
  {
    ParseLandmarks(root["landmarks"], source, scene);
  }
  if (root.contains("region_of_interest"))
  {
    ParseRegionOfInterest(root["region_of_interest"], source, scene);
  }
  if (root.contains("mesh"))
  {
    ParseMesh(root["mesh"], source, scene);
  }
  scene.Validate();
  return scene;
}

Scene
ReadScene(const std::string & fileName)
{
  std::ifstream in(fileName);
  if (!in)
  {
    FailInput("ReadScene", "cannot open scene file \"" + fileName + "\"");
  }
  std::ostringstream text;
  text << in.rdbuf();
  return ParseScene(text.str(), fileName);
}

} // namespace bmr
