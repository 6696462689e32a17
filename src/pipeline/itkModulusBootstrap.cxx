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
// Resampled intervals of the estimated moduli: the parametric bootstrap (resimulate from the estimate,
// revoxelize, re-estimate) and the rescan (revoxelize the fixed anatomy itself, re-mesh, re-estimate).
#include "itkPipelineStages.h"

#include "bmrParallel.h"
#include "bmrTaskTrace.h"

#include "bmrDisplacementFieldRasterizer.h"
#include "bmrError.h"
#include "bmrSimulation.h"
#include "bmrSurfaceMatchingObjective.h"
#include "itkBinaryThresholdImageFilter.h"
#include "itkGridGeometryConversion.h"
#include "itkLinearInterpolateImageFunction.h"
#include "itkMultiThreaderBase.h"
#include "itkPhysicsDeformationFieldSource.h"
#include "itkRegionOfInterestImageFilter.h"
#include "itkSceneDistanceMaps.h"
#include "itkSmoothingRecursiveGaussianImageFilter.h"

#include <atomic>
#include <cmath>
#include <functional>
#include <limits>
#include <mutex>
#include <random>

namespace itk {
namespace pipeline {
namespace {
using IndicatorImageType = Image<float, 3>;
using IndicatorInterpolatorType = LinearInterpolateImageFunction<IndicatorImageType, double>;
using Random = std::mt19937_64;
/** How far beyond the objective organs [mm] the rescans' grids reach (and their distance maps are exact). */
constexpr double RescanMarginMM = 15.0;

/** The values of the scene's objective labels, in objective order. */
std::vector<std::int32_t>
ObjectiveValues(const bmr::Scene & scene)
{
  std::vector<std::int32_t> values;
  for (const bmr::ObjectiveTerm & term : scene.objective)
  {
    values.push_back(scene.FindLabel(term.label)->value);
  }
  return values;
}

/** The number of voxels of \a labels holding \a value. */
std::size_t
VoxelCount(const BiomechanicalLabelImageType * labels, std::int32_t value)
{
  std::size_t n = 0;
  for (ImageRegionConstIterator<BiomechanicalLabelImageType> it(labels, labels->GetBufferedRegion()); !it.IsAtEnd();
       ++it)
  {
    n += it.Get() == value ? 1 : 0;
  }
  return n;
}

/** The index box of the voxels holding one of \a values, widened by \a marginMM and clipped to the image: the
 * union of each value's detail::PaddedMaskBox(). */
ImageRegion<3>
LabelBox(const BiomechanicalLabelImageType * labels, const std::vector<std::int32_t> & values, double marginMM)
{
  ImageRegion<3> box;
  for (std::int32_t value : values)
  {
    const ImageRegion<3> organ = detail::PaddedMaskBox(labels, value, value, marginMM);
    if (organ.GetNumberOfPixels() == 0 || box.GetNumberOfPixels() == 0)
    {
      box = box.GetNumberOfPixels() == 0 ? organ : box;
      continue;
    }
    for (unsigned int a = 0; a < 3; ++a)
    {
      const IndexValueType first = std::min(box.GetIndex(a), organ.GetIndex(a));
      const IndexValueType last = std::max(box.GetUpperIndex()[a], organ.GetUpperIndex()[a]);
      box.SetIndex(a, first);
      box.SetSize(a, static_cast<SizeValueType>(last - first + 1));
    }
  }
  return box;
}

/** Shifts the smoothed indicator \a smooth of an organ of \a voxels voxels so that its 0.5 level encloses the
 * organ's volume: smoothing moves the 0.5 level of a convex organ inwards (by about sigma^2 times the mean
 * curvature), and on the spheres phantom that shrinkage alone made the rescans 6 % too soft at 1 mm voxels and
 * 13 % at 2 mm. The volume is measured at 2^3 sub-points per voxel of the transition band. */
void
PreserveVolume(IndicatorImageType * smooth, std::size_t voxels)
{
  const auto interpolator = IndicatorInterpolatorType::New();
  interpolator->SetInputImage(smooth);
  std::size_t        inside = 0; // sub-points of the voxels beyond the band
  std::vector<float> band;
  for (ImageRegionConstIteratorWithIndex<IndicatorImageType> it(smooth, smooth->GetBufferedRegion()); !it.IsAtEnd();
       ++it)
  {
    if (it.Get() >= 0.98f || it.Get() <= 0.02f)
    {
      inside += it.Get() >= 0.98f ? 8 : 0;
      continue;
    }
    for (int c = 0; c < 8; ++c)
    {
      ContinuousIndex<double, 3> x;
      for (unsigned int a = 0; a < 3; ++a)
      {
        x[a] = double(it.GetIndex()[a]) + ((c >> a) & 1 ? 0.25 : -0.25);
      }
      band.push_back(interpolator->IsInsideBuffer(x) ? float(interpolator->EvaluateAtContinuousIndex(x)) : 0.0f);
    }
  }
  const std::size_t target = 8 * voxels > inside ? 8 * voxels - inside : 0;
  if (target == 0 || target >= band.size())
  {
    return; // no band to speak of: leave the 0.5 level
  }
  std::nth_element(band.begin(), band.begin() + std::ptrdiff_t(target - 1), band.end(), std::greater<float>());
  const float shift = std::min(std::max(band[target - 1], 0.25f), 0.75f) - 0.5f;
  for (ImageRegionIterator<IndicatorImageType> it(smooth, smooth->GetBufferedRegion()); !it.IsAtEnd(); ++it)
  {
    it.Set(it.Get() - shift);
  }
}

/** An anatomy as a smooth function: each objective organ's indicator, cropped around the organs (and interpolated
 * between thick slices when asked: InterpolateLabelSlices()), smoothed by a Gaussian
 * (UncertaintySettings::smoothingVoxels of the crop's largest spacing) and shifted to preserve the organ's volume
 * (PreserveVolume()), so that its 0.5 level is a sub-voxel surface that can be revoxelized on any grid without
 * resampling the staircase a second time; an organ given as a probability image keeps that image. */
struct SmoothAnatomy
{
  std::vector<std::int32_t>                       values;
  std::vector<IndicatorImageType::Pointer>        indicators;
  std::vector<IndicatorInterpolatorType::Pointer> interpolators;

  SmoothAnatomy(const BiomechanicalLabelImageType * labels,
                const bmr::Scene &                  scene,
                double                              sigmaVoxels,
                bool                                interpolateSlices,
                const OrganProbabilityImages *      probabilities = nullptr)
    : values(ObjectiveValues(scene))
  {
    auto cropper = RegionOfInterestImageFilter<BiomechanicalLabelImageType, BiomechanicalLabelImageType>::New();
    cropper->SetInput(labels);
    cropper->SetRegionOfInterest(LabelBox(labels, values, 20.0));
    cropper->Update();
    const BiomechanicalLabelImageType::ConstPointer crop =
      interpolateSlices ? InterpolateLabelSlices(cropper->GetOutput())
                        : BiomechanicalLabelImageType::ConstPointer(cropper->GetOutput());
    double sigma = 0.0;
    for (unsigned int a = 0; a < 3; ++a)
    {
      sigma = std::max(sigma, sigmaVoxels * crop->GetSpacing()[a]);
    }
    for (std::size_t o = 0; o < values.size(); ++o)
    {
      const std::int32_t value = values[o];
      const auto         given =
        probabilities ? probabilities->find(scene.objective[o].label) : OrganProbabilityImages::const_iterator();
      if (probabilities && given != probabilities->end())
      {
        indicators.push_back(given->second);
        interpolators.push_back(IndicatorInterpolatorType::New());
        interpolators.back()->SetInputImage(indicators.back());
        continue;
      }
      auto inside = BinaryThresholdImageFilter<BiomechanicalLabelImageType, IndicatorImageType>::New();
      inside->SetInput(crop);
      inside->SetLowerThreshold(value);
      inside->SetUpperThreshold(value);
      inside->SetInsideValue(1.0f);
      inside->SetOutsideValue(0.0f);
      auto smooth = SmoothingRecursiveGaussianImageFilter<IndicatorImageType, IndicatorImageType>::New();
      smooth->SetInput(inside->GetOutput());
      smooth->SetSigma(sigma);
      smooth->Update();
      indicators.push_back(smooth->GetOutput());
      indicators.back()->DisconnectPipeline();
      PreserveVolume(indicators.back(), VoxelCount(crop.GetPointer(), value));
      interpolators.push_back(IndicatorInterpolatorType::New());
      interpolators.back()->SetInputImage(indicators.back());
    }
  }

  /** The smooth indicator of objective organ \a o at \a y [mm], in [0, 1]: 0 outside its crop. */
  double
  IndicatorAt(std::size_t o, const Point<double, 3> & y) const
  {
    ContinuousIndex<double, 3> index;
    return indicators[o]->TransformPhysicalPointToContinuousIndex(y, index)
             ? std::min(std::max(interpolators[o]->EvaluateAtContinuousIndex(index), 0.0), 1.0)
             : 0.0;
  }

  /** The first objective organ whose smooth indicator is >= 0.5 at \a y [mm], or 0. */
  std::int32_t
  LabelAt(const Point<double, 3> & y) const
  {
    for (std::size_t o = 0; o < values.size(); ++o)
    {
      if (IndicatorAt(o, y) >= 0.5)
      {
        return values[o];
      }
    }
    return 0;
  }
};

/** The forward model of the resamples: the moving labels meshed finer than the estimation (another mesh, not a
 * refinement of it), the estimated moduli, u = 0 on fixed walls and the estimated wall motion on the loaded
 * walls (solved once here, which factorizes a linear model for every resample). */
struct Resimulation
{
  bmr::TetrahedralMesh               mesh;
  std::unique_ptr<bmr::ForwardModel> model;
  std::vector<double>                forces;
  std::vector<double>                prescribed; ///< 3N [mm]: held walls, estimated wall motion
  std::vector<std::int32_t>          wallNodes;
  std::mutex                         solver; ///< CHOLMOD's workspace is shared by the solves
};

/** The estimated displacement [mm] at \a X: interpolated in the estimation mesh, or that of the nearest of
 * \a nearby nodes when X lies just outside it (the two meshes approximate the same wall differently). */
std::array<double, 3>
EstimatedDisplacementAt(const bmr::PointLocator &         locator,
                        const bmr::TetrahedralMesh &      estimated,
                        const std::vector<std::int32_t> & nearby,
                        const std::array<double, 3> &     X)
{
  std::array<double, 3> u{ { 0, 0, 0 } };
  if (bmr::InterpolateDisplacement(locator, estimated, estimated.displacement, X, u))
  {
    return u;
  }
  double       best = std::numeric_limits<double>::infinity();
  std::int32_t nearest = nearby.empty() ? 0 : nearby.front();
  for (std::int32_t n : nearby)
  {
    const double d = std::hypot(
      estimated.points[3 * n] - X[0], estimated.points[3 * n + 1] - X[1], estimated.points[3 * n + 2] - X[2]);
    if (d < best)
    {
      best = d;
      nearest = n;
    }
  }
  for (int c = 0; c < 3; ++c)
  {
    u[c] = estimated.displacement[3 * nearest + c];
  }
  return u;
}

/** The loaded-wall nodes of \a scene on \a mesh that nothing else holds. */
std::vector<std::int32_t>
FreeWallNodes(const bmr::Scene & scene, const bmr::TetrahedralMesh & mesh, const std::vector<std::int32_t> & held)
{
  std::vector<char> isHeld(mesh.GetNumberOfPoints(), 0);
  for (std::int32_t n : held)
  {
    isHeld[n] = 1;
  }
  std::vector<std::int32_t> nodes;
  for (const bmr::LoadedWall & wall : bmr::SceneLoadedWalls(scene, mesh))
  {
    for (std::int32_t n : wall.nodes)
    {
      if (!isHeld[n])
      {
        isHeld[n] = 1;
        nodes.push_back(n);
      }
    }
  }
  return nodes;
}

std::unique_ptr<Resimulation>
MakeResimulation(const EstimationSetup &             setup,
                 const RegistrationResult &          r,
                 const BiomechanicalLabelImageType * movingLabels,
                 StageClock &                        clock)
{
  bmr::Scene scene = ScaledMeshSizes(*setup.scene, setup.settings->uncertainty.simulationMeshScale);
  scene.mesh.randomSeed += 7919;
  auto s = std::make_unique<Resimulation>();
  s->mesh = MeshLabelImage(movingLabels, scene, clock, "uncertainty: resimulation mesh");
  clock.Begin("uncertainty: resimulation FEM");
  auto materials = bmr::SceneMaterials(scene);
  for (const bmr::UnknownModulus & unknown : r.unknowns)
  {
    materials[unknown.label].youngsModulus = r.youngsModulus.at(unknown.name);
  }
  const bmr::BoundaryConditions held = bmr::SceneBoundaryConditions(scene, s->mesh);
  s->wallNodes = FreeWallNodes(scene, s->mesh, held.dirichletNodes);
  s->forces = held.forces;
  s->prescribed.assign(3 * s->mesh.GetNumberOfPoints(), 0.0);
  for (std::size_t i = 0; i < held.dirichletNodes.size() && 3 * i + 2 < held.dirichletValues.size(); ++i)
  {
    for (int c = 0; c < 3; ++c)
    {
      s->prescribed[3 * held.dirichletNodes[i] + c] = held.dirichletValues[3 * i + c];
    }
  }
  const bmr::TetrahedralMesh & estimated = r.state.mesh;
  const bmr::PointLocator      locator(estimated.points, estimated.tetrahedra);
  std::vector<std::int32_t>    estimatedWall;
  for (const bmr::LoadedWall & wall : bmr::SceneLoadedWalls(*setup.scene, estimated))
  {
    estimatedWall.insert(estimatedWall.end(), wall.nodes.begin(), wall.nodes.end());
  }
  for (std::int32_t n : s->wallNodes)
  {
    const std::array<double, 3> X{ { s->mesh.points[3 * n], s->mesh.points[3 * n + 1], s->mesh.points[3 * n + 2] } };
    const std::array<double, 3> u = EstimatedDisplacementAt(locator, estimated, estimatedWall, X);
    for (int c = 0; c < 3; ++c)
    {
      s->prescribed[3 * n + c] = u[c];
    }
  }
  std::vector<std::int32_t> nodes = held.dirichletNodes;
  nodes.insert(nodes.end(), s->wallNodes.begin(), s->wallNodes.end());
  s->model = bmr::MakeForwardModel(scene, s->mesh, materials);
  s->model->SetConstrainedNodes(nodes);
  s->model->SolveState(s->forces, s->prescribed);
  clock.End(std::to_string(s->mesh.GetNumberOfTetrahedra()) + " tetrahedra");
  return s;
}

/** The resample's wall motion: the estimated one plus a smooth random field perpendicular to it, of
 * \a fraction times its local magnitude (Gaussian bumps of 15 mm at 8 random wall nodes, normalized to unit
 * RMS over the walls): how the walls may slide without changing the surfaces walls along normals can fit. */
std::vector<double>
PerturbedWallMotion(const Resimulation & s, Random & rng, double fraction)
{
  std::vector<double> prescribed = s.prescribed;
  if (fraction <= 0.0 || s.wallNodes.empty())
  {
    return prescribed;
  }
  constexpr int                            bumps = 8;
  constexpr double                         width = 15.0; // mm
  std::array<std::array<double, 6>, bumps> bump;
  for (auto & b : bump)
  {
    const std::int32_t n = s.wallNodes[rng() % s.wallNodes.size()];
    for (int c = 0; c < 3; ++c)
    {
      b[c] = s.mesh.points[3 * n + c];
      b[3 + c] = Uniform(rng, -1.0, 1.0);
    }
  }
  std::vector<std::array<double, 3>> g(s.wallNodes.size(), { { 0, 0, 0 } });
  double                             sum2 = 0.0;
  for (std::size_t i = 0; i < s.wallNodes.size(); ++i)
  {
    const double * X = &s.mesh.points[3 * s.wallNodes[i]];
    for (const auto & b : bump)
    {
      const double w = std::exp(-(std::pow(X[0] - b[0], 2) + std::pow(X[1] - b[1], 2) + std::pow(X[2] - b[2], 2)) /
                                (2.0 * width * width));
      for (int c = 0; c < 3; ++c)
      {
        g[i][c] += w * b[3 + c];
      }
    }
    sum2 += g[i][0] * g[i][0] + g[i][1] * g[i][1] + g[i][2] * g[i][2];
  }
  const double scale = fraction / std::sqrt(std::max(sum2 / double(g.size()), 1e-300));
  for (std::size_t i = 0; i < s.wallNodes.size(); ++i)
  {
    double *     u = &prescribed[3 * s.wallNodes[i]];
    const double norm = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    if (norm == 0.0)
    {
      continue;
    }
    const double along = (g[i][0] * u[0] + g[i][1] * u[1] + g[i][2] * u[2]) / norm;
    for (int c = 0; c < 3; ++c)
    {
      u[c] += scale * norm * (g[i][c] - along * u[c] / norm);
    }
  }
  return prescribed;
}

/** The crop of the fixed grid around the objective organs, shifted by a random sub-voxel offset and rotated
 * by a small random angle about its center: another scan of the same anatomy. */
bmr::GridGeometry
ResampleGrid(const bmr::GridGeometry & crop, Random & rng, const UncertaintySettings & u)
{
  std::array<double, 3> axis;
  for (auto & a : axis)
  {
    a = Uniform(rng, -1.0, 1.0);
  }
  const double norm = std::max(std::hypot(axis[0], axis[1], axis[2]), 1e-12);
  for (auto & a : axis)
  {
    a /= norm;
  }
  const double          angle = Uniform(rng, 0.0, u.rotationDegrees) * 3.14159265358979323846 / 180.0;
  const double          c = std::cos(angle), s = std::sin(angle);
  std::array<double, 9> R; // Rodrigues
  for (int i = 0; i < 3; ++i)
  {
    for (int j = 0; j < 3; ++j)
    {
      R[3 * i + j] = (i == j ? c : 0.0) + (1.0 - c) * axis[i] * axis[j];
    }
  }
  R[1] -= s * axis[2];
  R[2] += s * axis[1];
  R[3] += s * axis[2];
  R[5] -= s * axis[0];
  R[6] -= s * axis[1];
  R[7] += s * axis[0];
  const std::array<double, 3> center = crop.IndexToPoint(
    { { 0.5 * double(crop.size[0] - 1), 0.5 * double(crop.size[1] - 1), 0.5 * double(crop.size[2] - 1) } });
  bmr::GridGeometry g = crop;
  for (int i = 0; i < 3; ++i)
  {
    for (int j = 0; j < 3; ++j)
    {
      g.direction[3 * i + j] = 0.0;
      for (int k = 0; k < 3; ++k)
      {
        g.direction[3 * i + j] += R[3 * i + k] * crop.direction[3 * k + j];
      }
    }
  }
  std::array<double, 3> offset;
  for (int j = 0; j < 3; ++j)
  {
    offset[j] = (0.5 * double(crop.size[j] - 1) - Uniform(rng, -u.shiftVoxels, u.shiftVoxels)) * crop.spacing[j];
  }
  for (int i = 0; i < 3; ++i)
  {
    g.origin[i] = center[i];
    for (int j = 0; j < 3; ++j)
    {
      g.origin[i] -= g.direction[3 * i + j] * offset[j];
    }
  }
  return g;
}

/** The fixed organs of one resample on \a grid: each voxel x gets the anatomy's label at x + d(x), d the
 * pull-back of \a deformed's displacement (the resimulation; null: d = 0, the fixed anatomy rescanned), and
 * each organ of \a fractionOrgans its smooth indicator there (the resample's partial-volume image, when the
 * data came as probabilities). Returns the distance maps. */
std::map<std::string, Image<float, 3>::Pointer>
RevoxelizedMaps(const bmr::TetrahedralMesh *     deformed,
                const bmr::GridGeometry &        grid,
                const SmoothAnatomy &            anatomy,
                const bmr::Scene &               scene,
                const std::vector<std::string> & fractionOrgans,
                bool                             interpolateSlices)
{
  auto labels =
    MakeImageOnGrid<BiomechanicalLabelImageType>(grid, std::vector<std::int32_t>(grid.GetNumberOfVoxels(), 0));
  std::vector<std::pair<std::size_t, std::vector<float>>> fractions;
  for (const std::string & name : fractionOrgans)
  {
    for (std::size_t o = 0; o < scene.objective.size(); ++o)
    {
      if (scene.objective[o].label == name)
      {
        fractions.push_back({ o, std::vector<float>(grid.GetNumberOfVoxels(), 0.0f) });
      }
    }
  }
  BiomechanicalFieldType::Pointer field;
  if (deformed)
  {
    auto meshObject = TetrahedralMeshObject::New();
    meshObject->Set(*deformed);
    auto pull = PhysicsDeformationFieldSource<BiomechanicalFieldType>::New();
    pull->SetMesh(meshObject);
    pull->SetReferenceImage(labels);
    pull->Update();
    field = pull->GetOutput();
  }
  const auto *   d = field ? field->GetBufferPointer() : nullptr;
  std::int32_t * out = labels->GetBufferPointer();
  for (std::size_t v = 0; v < grid.GetNumberOfVoxels(); ++v)
  {
    const auto       x = grid.IndexToPoint({ { double(v % grid.size[0]),
                                               double((v / grid.size[0]) % grid.size[1]),
                                               double(v / (grid.size[0] * grid.size[1])) } });
    Point<double, 3> y;
    for (unsigned int c = 0; c < 3; ++c)
    {
      y[c] = x[c] + (d ? d[v][c] : 0.0);
    }
    out[v] = anatomy.LabelAt(y);
    for (auto & f : fractions)
    {
      f.second[v] = static_cast<float>(anatomy.IndicatorAt(f.first, y));
    }
  }
  OrganProbabilityImages probabilities;
  for (const auto & f : fractions)
  {
    probabilities[scene.objective[f.first].label] = MakeImageOnGrid<BiomechanicalProbabilityImageType>(grid, f.second);
  }
  // The grid is a crop that reaches RescanMarginMM beyond the organs: each organ's map, exact that far, on its own box.
  return ObjectiveDistanceMaps(labels, probabilities, scene, RescanMarginMM, interpolateSlices);
}

/** What the resamples revoxelize: the anatomy as a smooth function (the fixed one for the rescans, the moving one
 * for the bootstrap) and the crop of the fixed grid around the objective organs. */
struct ResampleSource
{
  SmoothAnatomy     anatomy;
  bmr::GridGeometry crop;
};

ResampleSource
MakeResampleSource(const EstimationSetup &             setup,
                   const BiomechanicalLabelImageType * movingLabels,
                   const BiomechanicalLabelImageType * fixedLabels)
{
  const UncertaintySettings & u = setup.settings->uncertainty;
  const bool                  interpolate = setup.settings->interpolateSlices;
  ResampleSource              source{ u.method == UncertaintyMethodEnum::Rescan
                                        ? SmoothAnatomy(
                               fixedLabels, *setup.scene, u.smoothingVoxels, interpolate, setup.probabilities)
                                        : SmoothAnatomy(movingLabels, *setup.scene, u.smoothingVoxels, interpolate),
                         GridGeometryOf(fixedLabels) };
  const ImageRegion<3> box = LabelBox(fixedLabels, source.anatomy.values, RescanMarginMM);
  Point<double, 3>     corner;
  fixedLabels->TransformIndexToPhysicalPoint(box.GetIndex(), corner);
  for (unsigned int a = 0; a < 3; ++a)
  {
    source.crop.origin[a] = corner[a];
    source.crop.size[a] = box.GetSize(a);
  }
  return source;
}

/** Rescan \a k's distance maps: the fixed anatomy revoxelized on its grid (the resample's ResampleDraw::Grid). */
DistanceMaps
RescanMaps(const ResampleSource & source, const EstimationSetup & setup, unsigned int k)
{
  const UncertaintySettings & u = setup.settings->uncertainty;
  Random                      rng = ResampleRandom(u, k, ResampleDraw::Grid);
  const bmr::GridGeometry     grid = ResampleGrid(source.crop, rng, u);
  return RevoxelizedMaps(
    nullptr, grid, source.anatomy, *setup.scene, setup.probabilityOrgans, setup.settings->interpolateSlices);
}

/** The moduli [kPa, unknowns' order] re-estimated from resample \a k: of the resimulated anatomy \a sim
 * (bootstrap), or of the fixed anatomy itself when \a sim is null (rescan), whose maps may be \a premade. */
std::vector<double>
Resample(unsigned int                        k,
         bmr::TetrahedralMesh *              prefetched,
         const EstimationSetup &             setup,
         Resimulation *                      sim,
         const ResampleSource *              source,
         DistanceMaps *                      premade,
         const RegistrationResult &          r,
         const BiomechanicalLabelImageType * movingLabels)
{
  const UncertaintySettings & u = setup.settings->uncertainty;
  // The estimation's own meshes at randomly scaled sizes (the coarse one as the registration makes it).
  std::vector<PipelineStage> untimed;
  StageClock                 quiet(nullptr, untimed);
  const bmr::Scene           scene = ResampleMeshScene(*setup.scene, u, k);
  const bmr::TetrahedralMesh fine =
    prefetched ? std::move(*prefetched) : MeshLabelImage(movingLabels, scene, quiet, "resample mesh");
  RegistrationSettings settings = *setup.settings;
  settings.estimator.outerStepTolerance = u.stepTolerance;
  EstimationSetup resample = setup;
  resample.settings = &settings;
  resample.prefetch = nullptr;
  resample.fine = &fine;
  resample.fineAfterSweep = nullptr;
  bmr::TetrahedralMesh coarse;
  if (u.warmStart)
  {
    // The fit's neighbourhood is where a rescan's minimum lies: no sweep, hence no coarse mesh.
    resample.coarse = nullptr;
    resample.warmStartModuli = r.youngsModulus;
    resample.warmStartRelativeCurvature = r.estimation.relativeCurvature;
  }
  else if (setup.coarse)
  {
    coarse = MeshLabelImage(movingLabels, ScaledMeshSizes(scene, setup.settings->coarseFactor), quiet, "coarse");
    resample.coarse = &coarse;
  }
  DistanceMaps maps;
  if (premade)
  {
    maps = std::move(*premade);
  }
  else if (!sim)
  {
    maps = RescanMaps(*source, setup, k);
  }
  else
  {
    Random                    motion = ResampleRandom(u, k, ResampleDraw::WallMotion);
    const std::vector<double> prescribed = PerturbedWallMotion(*sim, motion, u.tangentialWallFraction);
    bmr::TetrahedralMesh      deformed = sim->mesh;
    {
      const std::lock_guard<std::mutex> lock(sim->solver);
      sim->model->ForgetState(); // the resamples' order varies with the threads; their states must not
      deformed.displacement = sim->model->SolveState(sim->forces, prescribed);
    }
    Random                  gridRandom = ResampleRandom(u, k, ResampleDraw::Grid);
    const bmr::GridGeometry grid = ResampleGrid(source->crop, gridRandom, u);
    maps = RevoxelizedMaps(
      &deformed, grid, source->anatomy, *setup.scene, setup.probabilityOrgans, setup.settings->interpolateSlices);
  }
  const auto          optimizer = RunEstimation(resample, maps, false, nullptr);
  std::vector<double> moduli;
  for (const bmr::UnknownModulus & unknown : r.unknowns)
  {
    moduli.push_back(optimizer->GetEstimatedYoungsModuli().at(unknown.name));
  }
  return moduli;
}
/** Each unknown's interval from the resamples that did not fail (\a moduli: per resample, in the unknowns'
 * order; \a failures: per resample, empty when it succeeded). */
std::map<std::string, ModulusInterval>
IntervalsFromResamples(const RegistrationResult &               r,
                       const UncertaintySettings &              u,
                       const std::vector<std::vector<double>> & moduli,
                       const std::vector<std::string> &         failures)
{
  std::map<std::string, ModulusInterval> intervals;
  for (std::size_t m = 0; m < r.unknowns.size(); ++m)
  {
    std::vector<double> samples;
    for (std::size_t k = 0; k < moduli.size(); ++k)
    {
      if (failures[k].empty())
      {
        samples.push_back(moduli[k][m]);
      }
    }
    const bmr::UnknownModulus & unknown = r.unknowns[m];
    ModulusInterval &           interval = intervals[unknown.name];
    interval = BootstrapInterval(r.youngsModulus.at(unknown.name),
                                 samples,
                                 unknown,
                                 u.correctBias,
                                 IntervalHalfWidths(u.method, u.quantiles, samples.size()));
    interval.method = u.method == UncertaintyMethodEnum::Rescan ? "rescan" : "bootstrap";
    interval.quantiles = UsesCalibratedHalfWidths(u.method, u.quantiles) ? "calibrated" : "student";
  }
  return intervals;
}
} // namespace

RescanMapsPrefetch::RescanMapsPrefetch(const BiomechanicalLabelImageType * fixedLabels, const EstimationSetup & setup)
  : m_Task("rescan maps alongside", true, [this, fixedLabels, setup]() {
    const ResampleSource        source = MakeResampleSource(setup, nullptr, fixedLabels);
    const UncertaintySettings & u = setup.settings->uncertainty;
    for (unsigned int k = 0; k < u.resamples && !m_Stop; ++k)
    {
      m_Maps.push_back(RescanMaps(source, setup, k));
    }
  })
{}

RescanMapsPrefetch::~RescanMapsPrefetch()
{
  m_Stop = true; // the maps under way are finished and waited for by m_Task, their exception dropped
}

std::vector<DistanceMaps>
RescanMapsPrefetch::Finish()
{
  m_Task.Wait();
  return std::move(m_Maps);
}

std::map<std::string, ModulusInterval>
BootstrapModuli(const EstimationSetup &             setup,
                RegistrationResult &                r,
                const BiomechanicalLabelImageType * movingLabels,
                const BiomechanicalLabelImageType * fixedLabels,
                StageClock &                        clock)
{
  const UncertaintySettings & u = setup.settings->uncertainty;
  const bool                  rescan = u.method == UncertaintyMethodEnum::Rescan;
  const auto                  sim = rescan ? nullptr : MakeResimulation(setup, r, movingLabels, clock);
  clock.Begin("uncertainty: " + std::to_string(u.resamples) + (rescan ? " rescans" : " resamples"));
  // The rescans revoxelize the fixed anatomy (its probabilities where given), the bootstrap the moving one; the
  // rescans' maps may have been made while the fit ran.
  std::vector<DistanceMaps> premadeMaps =
    rescan && setup.rescanMaps ? setup.rescanMaps->Finish() : std::vector<DistanceMaps>();
  std::unique_ptr<const ResampleSource> source;
  if (premadeMaps.size() < u.resamples)
  {
    source = std::make_unique<const ResampleSource>(MakeResampleSource(setup, movingLabels, fixedLabels));
  }
  std::vector<bmr::TetrahedralMesh> prefetched =
    setup.prefetch ? setup.prefetch->Finish()
                   : (setup.resampleMeshes ? *setup.resampleMeshes : std::vector<bmr::TetrahedralMesh>());
  // The resamples side by side on the thread budget, each with an equal share of it for its own solves (the
  // estimate does not depend on either count).
  const unsigned int threads = ResampleThreads(u);
  EstimationSetup    pooled = setup;
  pooled.fineSolveThreads = std::max(1U, threads / std::max(1U, std::min(threads, u.resamples)));
  std::vector<std::vector<double>> moduli(u.resamples);
  std::vector<std::string>         failures(u.resamples);
  unsigned int                     finished = 0;
  std::mutex                       progress; // the observer hears one resample at a time
  bmr::ParallelFor("interval: resamples", static_cast<int>(u.resamples), threads, [&](int task, int) {
    const auto k = static_cast<unsigned int>(task);
    try
    {
      moduli[k] = Resample(k,
                           k < prefetched.size() && !prefetched[k].points.empty() ? &prefetched[k] : nullptr,
                           pooled,
                           sim.get(),
                           source.get(),
                           k < premadeMaps.size() ? &premadeMaps[k] : nullptr,
                           r,
                           movingLabels);
    }
    catch (const std::exception & e)
    {
      failures[k] = e.what();
    }
    const std::lock_guard<std::mutex> lock(progress);
    if (clock.GetObserver() != nullptr)
    {
      ++finished;
      clock.GetObserver()->Progress(double(finished) / u.resamples,
                                    std::to_string(finished) + " of " + std::to_string(u.resamples) + " done");
    }
  });
  clock.End();
  std::vector<std::string> warnings;
  for (unsigned int k = 0; k < u.resamples; ++k)
  {
    if (!failures[k].empty())
    {
      warnings.push_back("uncertainty: resample " + std::to_string(k) + " failed and is left out: " + failures[k]);
    }
  }
  clock.Warn(r.state.warnings, warnings);
  return IntervalsFromResamples(r, u, moduli, failures);
}

} // namespace pipeline
} // namespace itk
