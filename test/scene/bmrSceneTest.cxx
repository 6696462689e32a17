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
// Scene files: a valid scene parses and round-trips; every invalid entry is named in the error.
#include "bmrScene.h"
#include "bmrSimulation.h"
#include "bmrTestUtilities.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <map>

namespace {
const char * const ValidScene = R"({
  "units": {"length": "mm", "modulus": "kPa", "force": "mN"},
  "labels": [
    {"name": "air", "value": 0, "role": "outside"},
    {"name": "soft_tissue", "value": 1, "role": "material", "youngs_modulus_kPa": 10, "poisson_ratio": 0.35},
    {"name": "prostate", "value": 2, "role": "unknown_material", "youngs_modulus_kPa": 50, "poisson_ratio": 0.4,
     "bounds_kPa": [30, 300]},
    {"name": "bladder", "value": 3, "role": "hollow"},
    {"name": "bone", "value": 5, "role": "fixed"}
  ],
  "gauge": "soft_tissue",
  "force_surfaces": ["bladder"],
  "objective": [{"label": "prostate", "weight": 2}, {"label": "bladder"}],
  "loads": [{"surface": "bladder", "type": "radial_displacement", "center_mm": [0, -5, 30], "magnitude_mm": 6}],
  "region_of_interest": {"margin_mm": 20, "boundary": "free"},
  "mesh": {"cell_size_mm": 6, "facet_size_mm": 4, "facet_distance_mm": 1, "cell_size_per_label_mm": {"prostate": 3}}
})";

std::string
Replace(std::string text, const std::string & from, const std::string & to)
{
  const auto pos = text.find(from);
  if (pos == std::string::npos)
  {
    throw std::logic_error("test bug: \"" + from + "\" not in the scene");
  }
  return text.replace(pos, from.size(), to);
}
} // namespace

int
bmrSceneTest(int, char *[])
{
  using bmr::test::Expect;
  using bmr::test::ExpectException;
  using bmr::test::ToString;
  bool             ok = true;
  const bmr::Scene s = bmr::ParseScene(ValidScene, "valid.json");
  ok &= Expect(s.labels.size() == 5, "valid scene: 5 labels (got " + ToString(s.labels.size()) + ")");
  const bmr::SceneLabel * prostate = s.FindLabel("prostate");
  if (Expect(prostate != nullptr, "valid scene: a label named \"prostate\""))
  {
    ok &= Expect(prostate->role == bmr::LabelRoleEnum::UnknownMaterial, "valid scene: prostate is an unknown material");
    ok &= Expect(prostate->upperBound == 300,
                 "valid scene: prostate upper bound 300 kPa (got " + ToString(prostate->upperBound) + ")");
  }
  else
  {
    ok = false;
  }
  ok &= Expect(s.objective[0].weight == 2,
               "valid scene: objective[0] weight 2 (got " + ToString(s.objective[0].weight) + ")");
  ok &= Expect(s.objective[1].weight == 1,
               "valid scene: objective[1] weight defaults to 1 (got " + ToString(s.objective[1].weight) + ")");
  ok &= Expect(s.mesh.cellSizePerLabel.at(2) == 3,
               "valid scene: cell size 3 mm in the prostate (got " + ToString(s.mesh.cellSizePerLabel.at(2)) + ")");
  ok &= Expect(s.roiMargin == 20, "valid scene: region of interest margin 20 mm (got " + ToString(s.roiMargin) + ")");
  ok &= Expect(s.loads[0].magnitude == 6,
               "valid scene: loads[0] magnitude 6 mm (got " + ToString(s.loads[0].magnitude) + ")");
  const std::vector<std::int32_t> excluded = s.ExcludedLabels();
  ok &= Expect(excluded == std::vector<std::int32_t>({ 0, 3, 5 }),
               "excluded labels are exactly {0, 3, 5} (got " + ToString(excluded.size()) + " labels)");
  // Round trip through SceneToJson.
  const bmr::Scene again = bmr::ParseScene(bmr::SceneToJson(s), "roundtrip");
  ok &= Expect(bmr::SceneToJson(again) == bmr::SceneToJson(s), "SceneToJson o ParseScene o SceneToJson round trip");
  ok &= Expect(s.model == bmr::MaterialModelEnum::Linear, "the tissue model defaults to linear");
  const bmr::Scene nh =
    bmr::ParseScene(Replace(ValidScene, "\"gauge\"", "\"model\": \"neo_hookean\", \"gauge\""), "nh.json");
  ok &= Expect(nh.model == bmr::MaterialModelEnum::NeoHookean &&
                 bmr::ParseScene(bmr::SceneToJson(nh), "roundtrip").model == bmr::MaterialModelEnum::NeoHookean,
               "\"model\": \"neo_hookean\" is read and survives the round trip");
  // Local refinement near named labels: read, written, and refused with a label the scene does not have.
  const std::string refined =
    Replace(ValidScene,
            "\"cell_size_per_label_mm\"",
            "\"refine_near\": {\"labels\": [\"prostate\"], \"distance_mm\": 6, \"size_mm\": 1.5}, "
            "\"cell_size_per_label_mm\"");
  const bmr::Scene r = bmr::ParseScene(refined, "refined.json");
  ok &= Expect(r.mesh.Refines() && r.mesh.refineNearLabels == std::vector<std::int32_t>{ 2 } &&
                 r.mesh.refineDistance == 6.0 && r.mesh.refineSize == 1.5,
               "refine_near: 1.5 mm within 6 mm of the prostate (label 2)");
  ok &= Expect(bmr::SceneToJson(bmr::ParseScene(bmr::SceneToJson(r), "roundtrip")) == bmr::SceneToJson(r) &&
                 bmr::SceneToJson(r).find("refine_near") != std::string::npos,
               "refine_near survives the round trip");
  ok &= ExpectException(
    "refine_near with an unknown label",
    [&] { bmr::ParseScene(Replace(refined, "[\"prostate\"]", "[\"liver\"]"), "bad.json"); },
    "mesh.refine_near.labels");
  // Surface bounds per label and the sliver bound: read, written, and refused when unknown, not numbers or <= 0.
  const std::string facets =
    Replace(ValidScene,
            "\"cell_size_per_label_mm\"",
            "\"facet_size_per_label_mm\": {\"prostate\": 3.5}, \"facet_distance_per_label_mm\": "
            "{\"prostate\": 0.3, \"bladder\": 0.4}, \"sliver_bound_deg\": 4, \"cell_size_per_label_mm\"");
  const bmr::Scene f = bmr::ParseScene(facets, "facets.json");
  ok &= Expect(f.mesh.facetSizePerLabel == std::map<std::int32_t, double>{ { 2, 3.5 } } &&
                 f.mesh.facetDistancePerLabel == std::map<std::int32_t, double>{ { 2, 0.3 }, { 3, 0.4 } } &&
                 f.mesh.sliverBound == 4.0,
               "facet bounds per label: prostate 3.5 / 0.3 mm, bladder 0.4 mm; sliver bound 4 deg");
  ok &= Expect(bmr::SceneToJson(bmr::ParseScene(bmr::SceneToJson(f), "roundtrip")) == bmr::SceneToJson(f) &&
                 bmr::SceneToJson(f).find("facet_distance_per_label_mm") != std::string::npos,
               "facet bounds per label survive the round trip");
  ok &= Expect(s.mesh.sliverBound == 3.0 && s.mesh.facetSizePerLabel.empty(),
               "without the keys: sliver bound 3 deg, no facet bound per label");
  ok &= ExpectException(
    "facet_size_per_label_mm with an unknown label",
    [&] { bmr::ParseScene(Replace(facets, "{\"prostate\": 3.5}", "{\"liver\": 3.5}"), "bad.json"); },
    "mesh.facet_size_per_label_mm.liver");
  ok &= ExpectException(
    "facet_distance_per_label_mm not a number",
    [&] { bmr::ParseScene(Replace(facets, "\"bladder\": 0.4", "\"bladder\": \"fine\""), "bad.json"); },
    "mesh.facet_distance_per_label_mm.bladder");
  ok &= ExpectException(
    "facet_size_per_label_mm = 0",
    [&] { bmr::ParseScene(Replace(facets, "{\"prostate\": 3.5}", "{\"prostate\": 0}"), "bad.json"); },
    "mesh.facet_size_per_label_mm");
  ok &= ExpectException(
    "sliver_bound_deg = 0",
    [&] { bmr::ParseScene(Replace(facets, "\"sliver_bound_deg\": 4", "\"sliver_bound_deg\": 0"), "bad.json"); },
    "mesh.sliver_bound_deg");
  std::cout << "parse and round trip: " << (ok ? "ok" : "FAIL") << std::endl;
  // A tube load: the axis is normalized on reading and survives the round trip.
  const std::string tube = Replace(ValidScene, "\"magnitude_mm\": 6", "\"axis\": [0, 0, 2], \"magnitude_mm\": 6");
  const bmr::Scene  withAxis = bmr::ParseScene(tube, "tube.json");
  bool              axisOk = true;
  axisOk &= Expect(withAxis.loads[0].axis == std::array<double, 3>{ { 0, 0, 1 } },
                   "load axis [0, 0, 2] normalized to exactly (0, 0, 1)");
  axisOk &= Expect(withAxis.loads[0].magnitude == 6,
                   "tube load magnitude 6 mm (got " + ToString(withAxis.loads[0].magnitude) + ")");
  axisOk &= Expect(bmr::ParseScene(bmr::SceneToJson(withAxis), "roundtrip").loads[0].axis == withAxis.loads[0].axis,
                   "load axis survives the round trip exactly");
  std::cout << "load axis: " << (axisOk ? "ok" : "FAIL") << std::endl;
  ok &= axisOk;
  // The tube load moves wall nodes behind the center radially from the axis, those beyond it from the center:
  // one tetrahedron whose face {1, 2, 3} is bladder wall; center (0, 0, 15), axis +z, 6 mm.
  {
    bmr::Scene capsule = withAxis;
    capsule.loads[0].center = { { 0, 0, 15 } };
    bmr::TetrahedralMesh mesh;
    mesh.points = { 0, 0, -30, 13, 0, -10, 0, 13, -10, 0, 0, 28 };
    mesh.tetrahedra = { 0, 1, 2, 3 };
    mesh.labels = { 1 };
    mesh.boundaryFaces = { 1, 2, 3 };
    mesh.boundaryFaceLabels = { 3 };
    const bmr::BoundaryConditions bc = bmr::SceneBoundaryConditions(capsule, mesh);
    // Expected: node 1 -> (6, 0, 0), node 2 -> (0, 6, 0) (tube), node 3 -> (0, 0, 6) (cap).
    const std::vector<double> expected = { 6, 0, 0, 0, 6, 0, 0, 0, 6 };
    ok &= Expect(bc.dirichletNodes == std::vector<std::int32_t>({ 1, 2, 3 }),
                 "tube load: the Dirichlet nodes are exactly {1, 2, 3} (got " + ToString(bc.dirichletNodes.size()) +
                   " nodes)");
    double worst = 0.0;
    for (std::size_t i = 0; i < expected.size() && i < bc.dirichletValues.size(); ++i)
    {
      worst = std::max(worst, std::abs(bc.dirichletValues[i] - expected[i]));
    }
    // Exact up to rounding: the directions are unit vectors of axis-aligned differences.
    std::cout << "tube load directions: largest error " << worst << " mm" << std::endl;
    ok &= Expect(worst < 1e-12, "tube load directions exact to 1e-12 mm (got " + ToString(worst) + ")");
    // An ellipsoid load (semi-axes 26, 13, 13 about the center): the direction of node 1, (13, 0, -25)
    // from the center, is the ellipsoid's normal there, proportional to (13 / 26^2, 0, -25 / 13^2).
    bmr::Scene ellipsoid = capsule;
    ellipsoid.loads[0].axis = { { 0, 0, 0 } };
    ellipsoid.loads[0].semiAxes = { { 26, 13, 13 } };
    const bmr::BoundaryConditions be = bmr::SceneBoundaryConditions(ellipsoid, mesh);
    const double                  n[3] = { 13.0 / 676.0, 0.0, -25.0 / 169.0 };
    const double                  norm = std::sqrt(n[0] * n[0] + n[2] * n[2]);
    double                        worstEllipsoid = 0.0;
    for (int c = 0; c < 3; ++c)
    {
      worstEllipsoid = std::max(worstEllipsoid, std::abs(be.dirichletValues[c] - 6.0 * n[c] / norm));
    }
    std::cout << "ellipsoid load direction: largest error " << worstEllipsoid << " mm" << std::endl;
    ok &= Expect(worstEllipsoid < 1e-12,
                 "ellipsoid load along the normal exact to 1e-12 mm (got " + ToString(worstEllipsoid) + ")");
  }

  // Warnings about estimating a modulus from coarse labels (none without an unknown modulus). The valid
  // scene's facet distance is 1 mm: half the finest voxel is the limit, so 2 mm voxels pass, 1.5 mm ones do
  // not. (Voxels coarser than bmr::StatedModulusVoxelLimitMM are the registration's warning, with its statement:
  // biomechreg_thick_slices.)
  {
    const auto count = [](const std::vector<std::string> & w, const std::string & what) {
      return std::count_if(
        w.begin(), w.end(), [&](const std::string & m) { return m.find(what) != std::string::npos; });
    };
    const auto fine = s.EstimationWarnings(2.0);
    const auto facet = s.EstimationWarnings(1.5);
    bmr::Scene known = s;
    known.labels[2].role = bmr::LabelRoleEnum::Material;
    bmr::Scene half = s; // the limit reached, not exceeded
    half.mesh.facetDistance = 0.5;
    const auto known1 = known.EstimationWarnings(1.0);
    const auto half1 = half.EstimationWarnings(1.0);
    bool       warningsOk = true;
    warningsOk &= Expect(fine.empty(), "2 mm voxels: no warning (got " + ToString(fine.size()) + ")");
    warningsOk &= Expect(facet.size() == 1, "1.5 mm voxels: one warning (got " + ToString(facet.size()) + ")");
    warningsOk &= Expect(count(facet, "mesh.facet_distance_mm = 1 exceeds half the finest label voxel (0.75 mm)") == 1,
                         "1.5 mm voxels: one warning that the facet distance exceeds half the finest voxel");
    warningsOk &= Expect(known.EstimationWarnings(0.5).empty() && known1.empty(),
                         "no warning without an unknown modulus (got " + ToString(known1.size()) + ")");
    warningsOk &= Expect(half1.empty(),
                         "no warning when the limit is reached but not exceeded (got " + ToString(half1.size()) + ")");
    warningsOk &= Expect(bmr::VoxelLimitReason(3.0).find("label voxels of up to 3 mm: the modulus is reported as not "
                                                         "determined") == 0 &&
                           bmr::VoxelLimitReason(3.0, 2.5).find("at most 2.5 mm") != std::string::npos,
                         "the voxel limit's reason names the voxels and the limit, and says that no modulus is stated");
    std::cout << "estimation warnings: " << (warningsOk ? "ok" : "FAIL") << std::endl;
    ok &= warningsOk;
  }

  // Mesh resolution of a label: the unit cube cut into the six tetrahedra of the Kuhn triangulation
  // (edges 1, sqrt 2 and sqrt 3, 3 : 2 : 1 per element) has V = 1, A = 6 and
  // n = 2V / (A h) = 2 / (6 (3 + 2 sqrt 2 + sqrt 3) / 6), exact up to rounding; at 0.26 elements across
  // a simulated label is warned about, naming it, a hollow one is not.
  {
    bmr::TetrahedralMesh cube;
    for (int k = 0; k < 8; ++k)
    {
      cube.points.insert(cube.points.end(), { double(k & 1), double((k >> 1) & 1), double((k >> 2) & 1) });
    }
    const int paths[6][2] = { { 1, 3 }, { 1, 5 }, { 2, 3 }, { 2, 6 }, { 4, 5 }, { 4, 6 } };
    for (const auto & p : paths)
    {
      cube.tetrahedra.insert(cube.tetrahedra.end(), { 0, p[0], p[1], 7 });
      cube.labels.push_back(1);
    }
    const auto   resolution = bmr::ComputeLabelResolution(cube);
    const double expected = 2.0 / (3.0 + 2.0 * std::sqrt(2.0) + std::sqrt(3.0));
    bmr::Scene   material = s;
    material.labels[1].value = 1; // soft_tissue
    bmr::Scene hollow = material;
    hollow.labels[1].role = bmr::LabelRoleEnum::Hollow;
    const auto warnings = bmr::MeshResolutionWarnings(material, cube);
    bool       resolutionOk = true;
    if (Expect(resolution.size() == 1, "resolution of one label (got " + ToString(resolution.size()) + ")"))
    {
      resolutionOk &= Expect(std::abs(resolution[0].volume - 1.0) < 1e-12,
                             "unit cube volume 1 to 1e-12 (got " + ToString(resolution[0].volume) + ")");
      resolutionOk &= Expect(std::abs(resolution[0].surfaceArea - 6.0) < 1e-12,
                             "unit cube surface area 6 to 1e-12 (got " + ToString(resolution[0].surfaceArea) + ")");
      resolutionOk &= Expect(std::abs(resolution[0].elementsAcross - expected) < 1e-12,
                             "elements across " + ToString(expected) + " to 1e-12 (got " +
                               ToString(resolution[0].elementsAcross) + ")");
    }
    else
    {
      resolutionOk = false;
    }
    if (Expect(warnings.size() == 1, "one mesh resolution warning (got " + ToString(warnings.size()) + ")"))
    {
      resolutionOk &= Expect(warnings[0].find("label \"soft_tissue\" is only 0.26 elements across") == 0,
                             "the warning starts with: label \"soft_tissue\" is only 0.26 elements across (got \"" +
                               warnings[0] + "\")");
    }
    else
    {
      resolutionOk = false;
    }
    const auto hollowWarnings = bmr::MeshResolutionWarnings(hollow, cube);
    resolutionOk &= Expect(hollowWarnings.empty(),
                           "no resolution warning for a hollow label (got " + ToString(hollowWarnings.size()) + ")");
    std::cout << "label resolution: " << (resolutionOk ? "ok" : "FAIL") << std::endl;
    ok &= resolutionOk;
  }

  auto              parse = [](const std::string & text) { return [text] { bmr::ParseScene(text, "bad.json"); }; };
  const std::string v = ValidScene;
  ok &= ExpectException("nu = 0.5",
                        parse(Replace(v, "\"poisson_ratio\": 0.35", "\"poisson_ratio\": 0.5")),
                        "labels[soft_tissue].poisson_ratio");
  ok &= ExpectException("E <= 0",
                        parse(Replace(v, "\"youngs_modulus_kPa\": 10", "\"youngs_modulus_kPa\": 0")),
                        "labels[soft_tissue].youngs_modulus_kPa");
  ok &= ExpectException(
    "unknown key", parse(Replace(v, "\"gauge\"", "\"gauge_typo\": 1, \"gauge\"")), "scene.gauge_typo: unknown key");
  ok &= ExpectException("unknown model",
                        parse(Replace(v, "\"gauge\"", "\"model\": \"hyperelastic\", \"gauge\"")),
                        "model: \"hyperelastic\" is not linear or neo_hookean");
  ok &= ExpectException(
    "neo-Hookean with nodal-averaged pressure",
    [&] {
      bmr::Scene bad = bmr::ParseScene(v, "bad.json");
      bad.model = bmr::MaterialModelEnum::NeoHookean;
      bad.formulation = bmr::ElementFormulationEnum::NodalAveragedPressure;
      bad.Validate();
    },
    "only the standard P1 formulation");
  ok &= ExpectException("wrong type",
                        parse(Replace(v, "\"margin_mm\": 20", "\"margin_mm\": \"20\"")),
                        "region_of_interest.margin_mm: must be a number");
  ok &=
    ExpectException("unknown role", parse(Replace(v, "\"role\": \"hollow\"", "\"role\": \"empty\"")), "labels[3].role");
  ok &= ExpectException("undefined objective label",
                        parse(Replace(v, "{\"label\": \"bladder\"}", "{\"label\": \"liver\"}")),
                        "objective[1].label: \"liver\" is not a label");
  ok &= ExpectException("loads on a material",
                        parse(Replace(v, "\"surface\": \"bladder\"", "\"surface\": \"prostate\"")),
                        "loads[0].surface");
  ok &= ExpectException("zero load axis",
                        parse(Replace(v, "\"magnitude_mm\": 6", "\"axis\": [0, 0, 0], \"magnitude_mm\": 6")),
                        "loads[0].axis: must be a non-zero direction");
  ok &= ExpectException("bounds", parse(Replace(v, "[30, 300]", "[60, 300]")), "labels[prostate].bounds_kPa");
  ok &= ExpectException("duplicate value", parse(Replace(v, "\"value\": 5", "\"value\": 3")), "labels[bone].value");
  ok &= ExpectException("broken JSON", parse("{\"labels\": ["), "bad.json: JSON");
  ok &=
    ExpectException("wrong unit", parse(Replace(v, "\"modulus\": \"kPa\"", "\"modulus\": \"Pa\"")), "units.modulus");
  // Nothing against rigid-body motion: no fixed label, no displacement load, free boundary, no estimated walls.
  ok &= ExpectException("rigid body",
                        parse(Replace(Replace(Replace(v, "\"role\": \"fixed\"", "\"role\": \"hollow\""),
                                              "\"force_surfaces\": [\"bladder\"]",
                                              "\"force_surfaces\": []"),
                                      "radial_displacement\", \"center_mm\": [0, -5, 30], \"magnitude_mm\": 6",
                                      "pressure\", \"pressure_kPa\": 1")),
                        "nothing prevents rigid-body motion");
  // Against the labels of an image.
  ok &= ExpectException(
    "label absent from the image",
    [&] {
      s.ValidateAgainstLabels({ 0, 1, 3, 5 }, "img.nrrd");
    },
    "labels[prostate]: label \"prostate\" (value 2) is absent from img.nrrd");
  ok &= ExpectException(
    "undescribed image label",
    [&] {
      s.ValidateAgainstLabels({ 0, 1, 2, 3, 5, 9 }, "img.nrrd");
    },
    "img.nrrd contains label 9");
  ok &= ExpectException(
    "missing file", [] { bmr::ReadScene("/nonexistent/scene.json"); }, "cannot open scene file");
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}
