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
#include "bmrSimulation.h"

#include "bmrDistanceLabels.h"
#include "bmrError.h"
#include "bmrNeoHookeanForwardModel.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <set>
#include <sstream>

namespace bmr {

std::vector<std::string>
MeshResolutionWarnings(const Scene & scene, const TetrahedralMesh & mesh)
{
  std::vector<std::string> warnings;
  for (const LabelResolution & r : ComputeLabelResolution(mesh))
  {
    const SceneLabel * l = scene.FindLabelValue(r.label);
    const bool simulated = l && (l->role == LabelRoleEnum::Material || l->role == LabelRoleEnum::UnknownMaterial);
    if (simulated && r.elementsAcross < MinimumElementsAcross)
    {
      std::ostringstream os;
      os << std::setprecision(2) << "label \"" << l->name << "\" is only " << r.elementsAcross
         << " elements across (2 x volume / surface area " << 2.0 * r.volume / r.surfaceArea << " mm, mean edge "
         << r.meanEdgeLength
         << " mm): linear tetrahedra stiffen in so thin a layer; reduce mesh.cell_size_mm or its "
            "cell_size_per_label_mm";
      warnings.push_back(os.str());
    }
  }
  return warnings;
}

std::map<std::int32_t, MaterialParameters>
SceneMaterials(const Scene & scene)
{
  std::map<std::int32_t, MaterialParameters> materials;
  for (const auto & l : scene.labels)
  {
    if (l.role == LabelRoleEnum::Material || l.role == LabelRoleEnum::UnknownMaterial)
    {
      materials[l.value] = MaterialParameters{ l.youngsModulus, l.poissonRatio, scene.formulation };
    }
  }
  return materials;
}

namespace {
// The label values present in the image; labels come in long runs: only a change of value needs a set look-up.
std::set<std::int32_t>
PresentLabels(const std::int32_t * labels, std::size_t n)
{
  std::set<std::int32_t> present;
  for (std::size_t v = 0; v < n; ++v)
  {
    if (v == 0 || labels[v] != labels[v - 1])
    {
      present.insert(labels[v]);
    }
  }
  return present;
}

// Labels that define the region of interest (neither plain known material nor outside).
std::set<std::int32_t>
RegionOfInterestLabels(const Scene & scene)
{
  std::set<std::int32_t> roiLabels;
  for (const auto & l : scene.labels)
  {
    if (l.role != LabelRoleEnum::Material && l.role != LabelRoleEnum::Outside)
    {
      roiLabels.insert(l.value);
    }
  }
  return roiLabels;
}

// Region of interest: box [lo, hi] (voxel indices) around the labels that are not plain known material,
// widened by scene.roiMargin; the whole grid when the scene sets no margin or no such label is present.
void
RegionOfInterestBox(const std::int32_t *           labels,
                    const GridGeometry &           grid,
                    const Scene &                  scene,
                    const std::set<std::int32_t> & roiLabels,
                    std::array<std::size_t, 3> &   lo,
                    std::array<std::size_t, 3> &   hi)
{
  lo = { { 0, 0, 0 } };
  hi = { { grid.size[0] - 1, grid.size[1] - 1, grid.size[2] - 1 } };
  if (scene.roiMargin >= 0.0)
  {
    std::array<std::int64_t, 3> blo{ { std::numeric_limits<std::int64_t>::max(),
                                       std::numeric_limits<std::int64_t>::max(),
                                       std::numeric_limits<std::int64_t>::max() } };
    std::array<std::int64_t, 3> bhi{ { -1, -1, -1 } };
    for (std::size_t k = 0; k < grid.size[2]; ++k)
      for (std::size_t j = 0; j < grid.size[1]; ++j)
        for (std::size_t i = 0; i < grid.size[0]; ++i)
        {
          if (roiLabels.count(labels[i + grid.size[0] * (j + grid.size[1] * k)]) > 0)
          {
            const std::int64_t idx[3] = { static_cast<std::int64_t>(i),
                                          static_cast<std::int64_t>(j),
                                          static_cast<std::int64_t>(k) };
            for (int d = 0; d < 3; ++d)
            {
              blo[d] = std::min(blo[d], idx[d]);
              bhi[d] = std::max(bhi[d], idx[d]);
            }
          }
        }
    if (bhi[0] >= 0)
    {
      for (int d = 0; d < 3; ++d)
      {
        const auto m = static_cast<std::int64_t>(std::ceil(scene.roiMargin / grid.spacing[d]));
        lo[d] = static_cast<std::size_t>(std::max<std::int64_t>(0, blo[d] - m));
        hi[d] =
          static_cast<std::size_t>(std::min<std::int64_t>(static_cast<std::int64_t>(grid.size[d]) - 1, bhi[d] + m));
      }
    }
  }
}

// The labels in the box [lo, hi], with the outside labels set to 0; roi receives the box's grid.
std::vector<std::int32_t>
CropLabels(const std::int32_t *               labels,
           const GridGeometry &               grid,
           const std::array<std::size_t, 3> & lo,
           const std::array<std::size_t, 3> & hi,
           const std::vector<std::int32_t> &  outside,
           GridGeometry &                     roi)
{
  roi = grid;
  for (int d = 0; d < 3; ++d)
  {
    roi.size[d] = hi[d] - lo[d] + 1;
  }
  roi.origin =
    grid.IndexToPoint({ { static_cast<double>(lo[0]), static_cast<double>(lo[1]), static_cast<double>(lo[2]) } });
  std::vector<std::int32_t> cropped(roi.GetNumberOfVoxels());
  for (std::size_t k = 0; k < roi.size[2]; ++k)
    for (std::size_t j = 0; j < roi.size[1]; ++j)
      for (std::size_t i = 0; i < roi.size[0]; ++i)
      {
        std::int32_t v = labels[(i + lo[0]) + grid.size[0] * ((j + lo[1]) + grid.size[1] * (k + lo[2]))];
        if (std::find(outside.begin(), outside.end(), v) != outside.end())
        {
          v = 0;
        }
        cropped[i + roi.size[0] * (j + roi.size[1] * k)] = v;
      }
  return cropped;
}

void
CheckMinimumDihedralAngle(const Scene & scene, const TetrahedralMesh & mesh)
{
  const MeshQuality quality = ComputeMeshQuality(mesh);
  if (quality.sharpestElement >= 0 && quality.minimumDihedralAngleDegrees < scene.mesh.minimumDihedralAngle)
  {
    const auto         e = static_cast<std::size_t>(quality.sharpestElement);
    const SceneLabel * l = scene.FindLabelValue(mesh.labels[e]);
    double             centroid[3] = { 0.0, 0.0, 0.0 };
    for (int i = 0; i < 4; ++i)
    {
      for (int c = 0; c < 3; ++c)
      {
        centroid[c] += 0.25 * mesh.points[3 * static_cast<std::size_t>(mesh.tetrahedra[4 * e + i]) + c];
      }
    }
    std::ostringstream msg;
    msg << "element " << e << " (label \"" << (l ? l->name : std::to_string(mesh.labels[e])) << "\", centroid ["
        << centroid[0] << ", " << centroid[1] << ", " << centroid[2] << "] mm) has a dihedral angle of "
        << quality.minimumDihedralAngleDegrees
        << " deg, below mesh.minimum_dihedral_angle_deg = " << scene.mesh.minimumDihedralAngle
        << ": enable mesh.optimize (sliver perturbation) or mesh.exude";
    Fail("MeshSceneLabels", msg.str());
  }
}

// Every present simulated label has elements and every present fixed or hollow label has its wall.
void
CheckPresentLabelsMeshed(const Scene & scene, const std::set<std::int32_t> & present, const TetrahedralMesh & mesh)
{
  std::set<std::int32_t> meshed(mesh.labels.begin(), mesh.labels.end());
  std::set<std::int32_t> walls(mesh.boundaryFaceLabels.begin(), mesh.boundaryFaceLabels.end());
  for (const auto & l : scene.labels)
  {
    if (present.count(l.value) == 0)
    {
      continue;
    }
    const bool simulated = l.role == LabelRoleEnum::Material || l.role == LabelRoleEnum::UnknownMaterial;
    if (simulated && meshed.count(l.value) == 0)
    {
      Fail("MeshSceneLabels",
           "label \"" + l.name +
             "\" is in the image but has no element after meshing (too small "
             "for mesh.cell_size_mm / facet_size_mm?)");
    }
    if ((l.role == LabelRoleEnum::Fixed || l.role == LabelRoleEnum::Hollow) && walls.count(l.value) == 0)
    {
      Fail("MeshSceneLabels",
           "the wall of label \"" + l.name +
             "\" is missing from the mesh (is it touching the "
             "simulated tissue?)");
    }
  }
}
} // namespace

namespace {
/** What MeshSceneLabels() and MeshSceneFunction() mesh: the region of interest's grid and voxels (outside labels
 * as 0), the mesh sizes (excluded labels coarse) and what the result is checked against. */
struct SceneMeshInput
{
  GridGeometry              roi;
  std::vector<std::int32_t> cropped;
  MeshingParameters         parameters;
  std::vector<std::int32_t> outside;
  std::vector<std::int32_t> excluded;
  std::set<std::int32_t>    present;
};

SceneMeshInput
PrepareSceneMesh(const std::int32_t * labels, const GridGeometry & grid, const Scene & scene)
{
  grid.Validate("moving label image");
  SceneMeshInput in;
  in.outside = scene.OutsideLabels();
  in.present = PresentLabels(labels, grid.GetNumberOfVoxels());
  scene.ValidateAgainstLabels(in.present, "the moving label image");
  std::array<std::size_t, 3> lo, hi;
  RegionOfInterestBox(labels, grid, scene, RegionOfInterestLabels(scene), lo, hi);
  in.cropped = CropLabels(labels, grid, lo, hi, in.outside, in.roi);
  // Excluded regions only contribute their surface: mesh their interior coarsely.
  in.parameters = scene.mesh;
  in.excluded = scene.ExcludedLabels();
  for (std::int32_t v : in.excluded)
  {
    if (in.parameters.cellSizePerLabel.count(v) == 0)
    {
      in.parameters.cellSizePerLabel[v] = 4.0 * in.parameters.cellSize;
    }
  }
  return in;
}

TetrahedralMesh
FinishSceneMesh(const TetrahedralMesh & full, const Scene & scene, const SceneMeshInput & in)
{
  TetrahedralMesh mesh = ExtractSubmesh(full, in.excluded);
  CheckMinimumDihedralAngle(scene, mesh);
  CheckPresentLabelsMeshed(scene, in.present, mesh);
  return mesh;
}
} // namespace

TetrahedralMesh
MeshSceneLabels(const std::int32_t * labels, const GridGeometry & grid, const Scene & scene)
{
  const SceneMeshInput in = PrepareSceneMesh(labels, grid, scene);
  if (scene.mesh.labelSurfaces == MeshingParameters::LabelSurfaces::Distance)
  {
    return FinishSceneMesh(
      MeshImplicitLabelsOnGrid(DistanceLabelFunction(in.cropped, in.roi), in.roi, in.cropped, in.parameters),
      scene,
      in);
  }
  return FinishSceneMesh(MeshLabelVolume(in.cropped.data(), in.roi, in.parameters), scene, in);
}

TetrahedralMesh
MeshSceneFunction(const std::function<std::int32_t(double, double, double)> & labelAt,
                  const std::int32_t *                                        labels,
                  const GridGeometry &                                        grid,
                  const Scene &                                               scene)
{
  if (!labelAt)
  {
    Fail("MeshSceneFunction", "no labeling function given");
  }
  const SceneMeshInput in = PrepareSceneMesh(labels, grid, scene);
  const auto           simulated = [&labelAt, &in](double x, double y, double z) -> std::int32_t {
    const std::int32_t v = labelAt(x, y, z);
    return std::find(in.outside.begin(), in.outside.end(), v) == in.outside.end() ? v : 0;
  };
  return FinishSceneMesh(MeshImplicitLabelsOnGrid(simulated, in.roi, in.cropped, in.parameters), scene, in);
}

namespace {
/** Prescribes a radial-displacement load's wall motion on the nodes of its surface \a label. */
void
PrescribeRadialDisplacement(const SceneLoad &       load,
                            std::int32_t            label,
                            const TetrahedralMesh & mesh,
                            std::vector<char> &     isDirichlet,
                            std::vector<double> &   value)
{
  for (std::int32_t node : NodesOnBoundary(mesh, label))
  {
    double d[3], along = 0.0, r = 0.0;
    for (int c = 0; c < 3; ++c)
    {
      d[c] = mesh.points[3 * node + c] - load.center[c];
      along += d[c] * load.axis[c];
    }
    // Behind the center along the axis: radial from the axis (the tube); otherwise from the center (the cap).
    // With semi-axes: the normal of the ellipsoid through the node.
    for (int c = 0; c < 3; ++c)
    {
      d[c] -= std::min(along, 0.0) * load.axis[c];
      if (load.semiAxes[c] > 0.0)
      {
        d[c] /= load.semiAxes[c] * load.semiAxes[c];
      }
      r += d[c] * d[c];
    }
    r = std::sqrt(r);
    if (r <= 0.0)
    {
      Fail("SceneBoundaryConditions", "loads on \"" + load.surface + "\": a wall node lies on center_mm");
    }
    isDirichlet[node] = 1;
    for (int c = 0; c < 3; ++c)
    {
      value[3 * node + c] = load.magnitude * d[c] / r;
    }
  }
}

/** Adds a pressure load's nodal forces on the boundary faces of its surface \a label into \a forces. */
void
AddPressureForces(const SceneLoad &       load,
                  std::int32_t            label,
                  const TetrahedralMesh & mesh,
                  std::vector<double> &   forces)
{
  // Boundary faces point out of the tissue, into the lumen; the lumen's pressure pushes back into the tissue.
  for (std::size_t f = 0; f < mesh.boundaryFaceLabels.size(); ++f)
  {
    if (mesh.boundaryFaceLabels[f] != label)
    {
      continue;
    }
    const double * x0 = &mesh.points[3 * mesh.boundaryFaces[3 * f]];
    const double * x1 = &mesh.points[3 * mesh.boundaryFaces[3 * f + 1]];
    const double * x2 = &mesh.points[3 * mesh.boundaryFaces[3 * f + 2]];
    const double   a[3] = { x1[0] - x0[0], x1[1] - x0[1], x1[2] - x0[2] };
    const double   b[3] = { x2[0] - x0[0], x2[1] - x0[1], x2[2] - x0[2] };
    const double   areaNormal[3] = { 0.5 * (a[1] * b[2] - a[2] * b[1]),
                                     0.5 * (a[2] * b[0] - a[0] * b[2]),
                                     0.5 * (a[0] * b[1] - a[1] * b[0]) };
    for (int k = 0; k < 3; ++k)
    {
      for (int c = 0; c < 3; ++c)
      {
        forces[3 * mesh.boundaryFaces[3 * f + k] + c] -= load.magnitude * areaNormal[c] / 3.0;
      }
    }
  }
}

/** The boundary labels held fixed: the fixed labels, then the region of interest's boundary (0) when it is fixed. */
std::vector<std::int32_t>
FixedWallLabels(const Scene & scene)
{
  std::vector<std::int32_t> fixedWalls;
  for (const auto & l : scene.labels)
  {
    if (l.role == LabelRoleEnum::Fixed)
    {
      fixedWalls.push_back(l.value);
    }
  }
  if (scene.roiBoundaryFixed)
  {
    fixedWalls.push_back(0);
  }
  return fixedWalls;
}
} // namespace

BoundaryConditions
SceneBoundaryConditions(const Scene & scene, const TetrahedralMesh & mesh)
{
  const std::size_t  N = mesh.GetNumberOfPoints();
  BoundaryConditions bc;
  bc.forces.assign(3 * N, 0.0);
  std::vector<char>   isDirichlet(N, 0);
  std::vector<double> value(3 * N, 0.0);
  for (const auto & load : scene.loads)
  {
    const std::int32_t label = scene.FindLabel(load.surface)->value;
    if (load.type == SceneLoad::TypeEnum::RadialDisplacement)
    {
      PrescribeRadialDisplacement(load, label, mesh, isDirichlet, value);
    }
    else
    {
      AddPressureForces(load, label, mesh, bc.forces);
    }
  }
  for (std::int32_t label : FixedWallLabels(scene))
  {
    for (std::int32_t node : NodesOnBoundary(mesh, label))
    {
      isDirichlet[node] = 1;
      value[3 * node] = value[3 * node + 1] = value[3 * node + 2] = 0.0;
    }
  }
  for (std::size_t node = 0; node < N; ++node)
  {
    if (isDirichlet[node])
    {
      bc.dirichletNodes.push_back(static_cast<std::int32_t>(node));
      bc.dirichletValues.insert(bc.dirichletValues.end(), &value[3 * node], &value[3 * node + 3]);
    }
  }
  return bc;
}

std::unique_ptr<ForwardModel>
MakeForwardModel(const Scene &                                      scene,
                 const TetrahedralMesh &                            mesh,
                 const std::map<std::int32_t, MaterialParameters> & materials,
                 const NewtonSettings &                             newton)
{
  if (scene.model == MaterialModelEnum::NeoHookean)
  {
    return std::make_unique<NeoHookeanForwardModel>(mesh, materials, newton);
  }
  return std::make_unique<LinearForwardModel>(mesh, materials);
}

std::vector<double>
SceneVonMisesStress(const Scene &                                      scene,
                    const TetrahedralMesh &                            mesh,
                    const std::map<std::int32_t, MaterialParameters> & materials,
                    const std::vector<double> &                        u)
{
  if (scene.model == MaterialModelEnum::NeoHookean)
  {
    return NeoHookeanVonMisesStress(mesh, materials, u);
  }
  return LinearElasticModel(mesh, materials).ComputeVonMisesStress(u);
}

void
SetElementMaterials(const TetrahedralMesh &                            mesh,
                    const std::map<std::int32_t, MaterialParameters> & materials,
                    ForwardSimulation &                                simulation)
{
  simulation.youngsModulus.resize(mesh.GetNumberOfTetrahedra());
  simulation.poissonRatio.resize(mesh.GetNumberOfTetrahedra());
  for (std::size_t e = 0; e < mesh.GetNumberOfTetrahedra(); ++e)
  {
    simulation.youngsModulus[e] = materials.at(mesh.labels[e]).youngsModulus;
    simulation.poissonRatio[e] = materials.at(mesh.labels[e]).poissonRatio;
  }
}

std::vector<double>
PrescribedDisplacements(const BoundaryConditions & bc, std::size_t numberOfNodes)
{
  std::vector<double> prescribed(3 * numberOfNodes, 0.0);
  for (std::size_t k = 0; k < bc.dirichletNodes.size(); ++k)
  {
    std::copy(&bc.dirichletValues[3 * k], &bc.dirichletValues[3 * k] + 3, &prescribed[3 * bc.dirichletNodes[k]]);
  }
  return prescribed;
}

namespace {
// The neo-Hookean path of SimulateScene(): the same boundary conditions, Newton's equilibrium.
ForwardSimulation
SimulateNeoHookean(const Scene & scene, const TetrahedralMesh & mesh, const BoundaryConditions & bc)
{
  const auto             materials = SceneMaterials(scene);
  NeoHookeanForwardModel model(mesh, materials);
  model.SetConstrainedNodes(bc.dirichletNodes);
  ForwardSimulation out;
  out.displacement = model.SolveState(bc.forces, PrescribedDisplacements(bc, mesh.GetNumberOfPoints()));
  out.force = model.InternalForces(out.displacement);
  out.vonMises = model.VonMisesStress(out.displacement);
  SetElementMaterials(mesh, materials, out);
  out.timings.solve = model.GetStatistics().seconds;
  out.newtonIterations = model.GetStatistics().iterations;
  out.loadIncrements = model.GetStatistics().acceptedIncrements;
  out.factorizations = model.GetStatistics().factorizations;
  return out;
}
} // namespace

ForwardSimulation
SimulateScene(const Scene & scene, const TetrahedralMesh & mesh, unsigned threads)
{
  const BoundaryConditions bc = SceneBoundaryConditions(scene, mesh);
  ForwardSimulation        out;
  if (scene.model == MaterialModelEnum::NeoHookean)
  {
    out = SimulateNeoHookean(scene, mesh, bc);
  }
  else
  {
    LinearElasticModel model(mesh, SceneMaterials(scene));
    model.SetNumberOfSolveThreads(threads);
    model.SetDirichletConditions(bc.dirichletNodes, bc.dirichletValues);
    out.displacement = model.Solve(bc.forces);
    out.force = model.ComputeInternalForces(out.displacement);
    out.vonMises = model.ComputeVonMisesStress(out.displacement);
    out.youngsModulus = model.GetElementYoungsModuli();
    out.poissonRatio = model.GetElementPoissonRatios();
    out.timings = model.GetTimings();
  }
  out.dirichlet.assign(mesh.GetNumberOfPoints(), 0);
  for (std::int32_t node : bc.dirichletNodes)
  {
    out.dirichlet[node] = 1;
  }
  return out;
}

} // namespace bmr
