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
// The phantom pipeline: a moving/fixed pair with known moduli and wall loads, made without inverse crime.
#include "itkPipelineStages.h"
#include "itkMarkerPipeline.h"

#include "bmrError.h"
#include "bmrPhantom.h"
#include "bmrSimulation.h"
#include "bmrDisplacementFieldRasterizer.h"
#include "bmrTetrahedralMesh.h"
#include "itkGridGeometryConversion.h"
#include "itkVectorLinearInterpolateImageFunction.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <ostream>
#include <sstream>
#include <random>

namespace itk {
namespace {
/** Label of the tumour inside the prostate, in the truth's label map only. */
constexpr std::int32_t PelvisTumour = 6;

bool
IsPelvis(const PhantomSettings & s)
{
  return s.anatomy == PhantomSettings::AnatomyEnum::Pelvis;
}

bmr::PelvisPhantomParameters
PelvisParameters(const PhantomSettings & s)
{
  bmr::PelvisPhantomParameters p;
  p.grid = s.grid;
  const std::uint64_t planning = s.planningSeed != 0 ? s.planningSeed : s.seed;
  p.seedPlacementSeed = planning;
  p.numberOfSeeds = s.numberOfSeeds;
  p.noiseSigmaHU = s.noiseHU;
  p.noiseSeed = 1000 + planning;
  p.anatomy = s.organs;
  return p;
}

bmr::SpherePhantomParameters
SphereParameters(const PhantomSettings & s)
{
  bmr::SpherePhantomParameters p;
  p.grid = s.grid;
  return p;
}

bmr::PhantomVolume
MovingVolume(const PhantomSettings & s)
{
  if (IsPelvis(s))
  {
    return bmr::MakePelvisPhantom(PelvisParameters(s));
  }
  bmr::PhantomVolume moving = bmr::MakeSpherePhantom(SphereParameters(s));
  bmr::AddGaussianNoise(moving.ct, s.noiseHU, 1000 + (s.planningSeed != 0 ? s.planningSeed : s.seed));
  return moving;
}

/** The scene the registration of the pair is given: the prostate's modulus unknown, the landmark files named
 * when the anatomy has seeds. */
bmr::Scene
EstimationScene(const PhantomSettings & s, bool seeds)
{
  bmr::Scene scene = IsPelvis(s) ? bmr::PelvisPhantomScene(50.0, true) : bmr::SpherePhantomScene(50.0, true);
  scene.model = s.model;
  if (seeds)
  {
    scene.movingLandmarks = "landmarks_moving.csv";
    scene.fixedLandmarks = "landmarks_fixed.csv";
  }
  return scene;
}

/** Known moduli and wall loads, on a finer mesh with another random seed of the mesher. */
bmr::Scene
TruthScene(const PhantomSettings & s, const bmr::GridGeometry & grid)
{
  bmr::Scene truth = ScaledMeshSizes(IsPelvis(s) ? bmr::PelvisPhantomScene(s.prostateE, false, s.prostateNu)
                                                 : bmr::SpherePhantomScene(s.prostateE, false),
                                     s.truthRefinement);
  truth.mesh.randomSeed = 12345;
  for (bmr::SceneLabel & label : truth.labels)
  {
    if (label.name == (IsPelvis(s) ? "soft_tissue" : "outer"))
    {
      label.youngsModulus = s.tissueE;
    }
  }
  // The surfaces a further 0.8 x closer to the labels than the cells' scale: no uniform mesh scale of the
  // estimation scene (register --mesh-scale) can reproduce the truth's mesh.
  truth.mesh.facetDistance *= 0.8;
  if (s.truthRefineSize > 0.0)
  {
    truth.mesh.refineNearLabels = { IsPelvis(s) ? bmr::PelvisProstate : truth.FindLabel("inner")->value };
    truth.mesh.refineDistance = s.truthRefineDistance;
    truth.mesh.refineSize = s.truthRefineSize;
  }
  if (IsPelvis(s) && (s.bladderKPa > 0.0 || s.rectumKPa > 0.0))
  {
    // Pressure in the lumens: the walls move as the tissue lets them (no wall is driven into the prostate).
    truth.loads = { { "bladder", bmr::SceneLoad::TypeEnum::Pressure, { { 0, 0, 0 } }, s.bladderKPa },
                    { "rectum", bmr::SceneLoad::TypeEnum::Pressure, { { 0, 0, 0 } }, s.rectumKPa } };
  }
  else if (IsPelvis(s))
  {
    truth.loads = bmr::PelvisFillingLoads(PelvisParameters(s), s.bladderMM, s.rectumMM, s.filling);
  }
  else
  {
    truth.loads = { { "outside", bmr::SceneLoad::TypeEnum::RadialDisplacement, bmr::GridCenter(grid), -s.bladderMM } };
  }
  truth.Validate();
  return truth;
}

/** The index of voxel \a v (index 0 fastest). */
std::array<double, 3>
VoxelIndex(const bmr::GridGeometry & g, std::size_t v)
{
  return { { double(v % g.size[0]), double((v / g.size[0]) % g.size[1]), double(v / (g.size[0] * g.size[1])) } };
}

/** The truth may hold a stiffer tumour inside the prostate (dissertation Table 3.4): a ball at the prostate's
 * centroid with the requested fraction of its volume [mm], labeled only in the truth's label map (or anatomy) and
 * scene. The estimator sees one homogeneous prostate. */
struct TumourBall
{
  std::array<double, 3> center{ { 0, 0, 0 } };
  double                radius{ 0.0 };

  bool
  Contains(const std::array<double, 3> & x) const
  {
    return std::hypot(x[0] - center[0], x[1] - center[1], x[2] - center[2]) <= radius;
  }
};

TumourBall
TumourBallOf(const std::vector<std::int32_t> & labels, const bmr::GridGeometry & g, const PhantomSettings & s)
{
  TumourBall  ball;
  std::size_t n = 0;
  for (std::size_t v = 0; v < labels.size(); ++v)
  {
    if (labels[v] == bmr::PelvisProstate)
    {
      const auto x = g.IndexToPoint(VoxelIndex(g, v));
      for (int a = 0; a < 3; ++a)
      {
        ball.center[a] += x[a];
      }
      ++n;
    }
  }
  const double voxel = g.spacing[0] * g.spacing[1] * g.spacing[2];
  ball.radius = std::cbrt(s.tumourFraction * double(n) * voxel * 3.0 / (4.0 * 3.14159265358979));
  for (int a = 0; a < 3; ++a)
  {
    ball.center[a] /= double(std::max<std::size_t>(n, 1));
  }
  return ball;
}

/** Adds the tumour's label and material to the truth scene. */
void
AddTumourLabel(const PhantomSettings & s, bmr::Scene & truth)
{
  truth.labels.push_back({ "tumour", PelvisTumour, bmr::LabelRoleEnum::Material, s.tumourE, s.prostateNu });
  truth.mesh.cellSizePerLabel[PelvisTumour] = truth.mesh.cellSizePerLabel[bmr::PelvisProstate];
}

std::vector<std::int32_t>
WithTumour(std::vector<std::int32_t> labels, const bmr::GridGeometry & g, const TumourBall & ball)
{
  for (std::size_t v = 0; v < labels.size(); ++v)
  {
    if (labels[v] == bmr::PelvisProstate && ball.Contains(g.IndexToPoint(VoxelIndex(g, v))))
    {
      labels[v] = PelvisTumour;
    }
  }
  return labels;
}

/** The physical points x + d(x) of every voxel x of \a grid under the fixed -> moving \a field [mm]. */
std::vector<double>
PullBackPoints(const bmr::GridGeometry & grid, const BiomechanicalFieldType * field)
{
  std::vector<double> points(3 * grid.GetNumberOfVoxels());
  const auto *        d = field->GetBufferPointer();
  for (std::size_t v = 0; v < grid.GetNumberOfVoxels(); ++v)
  {
    const auto x = grid.IndexToPoint(VoxelIndex(grid, v));
    for (int c = 0; c < 3; ++c)
    {
      points[3 * v + c] = x[c] + d[v][c];
    }
  }
  return points;
}

/** The analytic anatomy as a function of the point (its labels at physical mm). */
bmr::PhantomLabelFunction
AnatomyLabelFunction(const PhantomSettings & s)
{
  if (IsPelvis(s))
  {
    return bmr::PelvisLabelFunction(PelvisParameters(s));
  }
  return bmr::SphereLabelFunction(SphereParameters(s));
}

/** The truth's mesh of the anatomy \a labelAt itself (bmr::MeshSceneFunction), whose voxelization \a labels is,
 * as one stage. */
bmr::TetrahedralMesh
MeshTruthAnatomy(const bmr::PhantomLabelFunction &   labelAt,
                 const BiomechanicalLabelImageType * labels,
                 const bmr::Scene &                  truth,
                 pipeline::StageClock &              clock)
{
  clock.Begin("mesh (CGAL Mesh_3, the anatomy's own surfaces)");
  const bmr::TetrahedralMesh mesh =
    bmr::MeshSceneFunction(labelAt, labels->GetBufferPointer(), GridGeometryOf(labels), truth);
  std::ostringstream detail;
  detail << mesh.GetNumberOfTetrahedra() << " tetrahedra, " << mesh.GetNumberOfPoints() << " nodes, min dihedral "
         << std::setprecision(1) << bmr::ComputeMeshQuality(mesh).minimumDihedralAngleDegrees << " deg";
  clock.End(detail.str());
  return mesh;
}

/** The deformed analytic anatomy's labels at \a points [mm, 3 per point]. */
std::vector<std::int32_t>
AnatomyLabelsAt(const PhantomSettings & s, const std::vector<double> & points)
{
  if (IsPelvis(s))
  {
    return bmr::PelvisLabelsAt(PelvisParameters(s), points);
  }
  return bmr::SphereLabelsAt(SphereParameters(s), points);
}

/** The fixed labels voxelize the deformed analytic anatomy once (the label at each voxel's pull-back
 * point), as a scan would; resampling the voxelized moving labels would quantize twice, and the second
 * staircase, carried along rigidly, favors the stiffest modulus. */
BiomechanicalLabelImageType::Pointer
FixedLabels(const PhantomSettings & s, const bmr::GridGeometry & grid, const BiomechanicalFieldType * field)
{
  return MakeImageOnGrid<BiomechanicalLabelImageType>(grid, AnatomyLabelsAt(s, PullBackPoints(grid, field)));
}

/** Seed centers moved by the simulated displacement: the ground-truth landmark pairs. */
/** \a grid with its origin moved by U(-shift, shift) voxels along each of its axes (mt19937_64(seed)'s raw
 * integers, whose sequence the standard fixes). */
bmr::GridGeometry
ShiftedGrid(const bmr::GridGeometry & grid, double shift, std::uint64_t seed)
{
  bmr::GridGeometry shifted = grid;
  std::mt19937_64   rng(seed);
  for (unsigned int a = 0; a < 3; ++a)
  {
    const double offset = shift * (2.0 * pipeline::Uniform(rng, 0.0, 1.0) - 1.0) * grid.spacing[a];
    for (unsigned int r = 0; r < 3; ++r)
    {
      shifted.origin[r] += grid.direction[3 * r + a] * offset;
    }
  }
  return shifted;
}

void
MoveSeeds(PhantomPair & pair, const std::vector<bmr::Seed> & seeds, const bmr::TetrahedralMesh & mesh)
{
  const bmr::PointLocator locator(mesh.points, mesh.tetrahedra);
  for (std::size_t i = 0; i < seeds.size(); ++i)
  {
    const auto &          X = seeds[i].center;
    std::array<double, 3> u;
    if (!bmr::InterpolateDisplacement(locator, mesh, mesh.displacement, X, u))
    {
      bmr::Fail("MakePhantomPair", "seed " + std::to_string(i) + " lies outside the simulated mesh");
    }
    pair.movingLandmarks.push_back({ "seed" + std::to_string(i), X });
    pair.fixedLandmarks.push_back({ "seed" + std::to_string(i), { { X[0] + u[0], X[1] + u[1], X[2] + u[2] } } });
  }
}
/** Per load surface of \a scene: the largest and the mean |u| [mm] over \a mesh's nodes on that wall (the
 * boundary faces towards the surface's label). */
std::map<std::string, std::array<double, 2>>
WallMotion(const bmr::Scene & scene, const bmr::TetrahedralMesh & mesh)
{
  std::map<std::string, std::array<double, 2>> motion;
  for (const bmr::SceneLoad & load : scene.loads)
  {
    const std::vector<std::int32_t> nodes = bmr::NodesOnBoundary(mesh, scene.FindLabel(load.surface)->value);
    double                          largest = 0.0, sum = 0.0;
    for (std::int32_t n : nodes)
    {
      const double * u = &mesh.displacement[3 * std::size_t(n)];
      const double   length = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
      largest = std::max(largest, length);
      sum += length;
    }
    motion[load.surface] = { { largest, nodes.empty() ? 0.0 : sum / double(nodes.size()) } };
  }
  return motion;
}
} // namespace

PhantomPair
MakePhantomPair(const PhantomSettings & s, PipelineObserver * observer)
{
  bmr::TetrahedralMesh truthMesh;
  return MakePhantomPair(s, observer, truthMesh);
}

namespace {
/** The fixed scan's own noise on top of the warped (noisy) moving one. */
void
AddFixedNoise(BiomechanicalCTImageType * fixedCT, const PhantomSettings & s)
{
  std::vector<float> noise(fixedCT->GetBufferedRegion().GetNumberOfPixels(), 0.0f);
  bmr::AddGaussianNoise(noise, s.noiseHU, 2000 + s.seed);
  float * p = fixedCT->GetBufferPointer();
  for (std::size_t i = 0; i < noise.size(); ++i)
  {
    p[i] += noise[i];
  }
}

/** The fixed organs' volume fractions and outline fractions, where \a s asks for them. */
void
AddFixedSubVoxelData(PhantomPair & pair, const PhantomSettings & s, pipeline::StageClock & clock)
{
  const auto anatomyAt = [&s](const std::vector<double> & points) { return AnatomyLabelsAt(s, points); };
  if (s.fractions)
  {
    clock.Begin("volume fractions of the fixed organs");
    pair.fixedFractions = pipeline::FixedVolumeFractions(pair.scene, pair.fixedLabels, pair.truthField, anatomyAt);
    clock.End();
  }
  if (s.contourFractions)
  {
    clock.Begin("outline fractions of the fixed organs");
    pair.fixedContourFractions =
      pipeline::FixedContourFractions(pair.scene, pair.fixedLabels, pair.truthField, anatomyAt);
    clock.End();
  }
}
} // namespace

PhantomPair
MakePhantomPair(const PhantomSettings &    s,
                PipelineObserver *         observer,
                bmr::TetrahedralMesh &     truthMesh,
                const PhantomMovingReady & movingReady)
{
  PhantomPair          pair;
  pipeline::StageClock clock(observer, pair.stages);
  clock.Begin("phantom volume");
  const bmr::PhantomVolume moving = MovingVolume(s);
  clock.End();

  pair.truthScene = TruthScene(s, moving.grid);
  pair.truthScene.model = s.model;
  pair.movingCT = MakeImageOnGrid<BiomechanicalCTImageType>(moving.grid, moving.ct);
  pair.movingLabels = MakeImageOnGrid<BiomechanicalLabelImageType>(moving.grid, moving.labels);
  pair.scene = EstimationScene(s, !moving.seeds.empty());
  if (movingReady)
  {
    movingReady(pair.movingLabels.GetPointer(), pair.scene);
  }
  BiomechanicalLabelImageType::Pointer truthLabels = pair.movingLabels;
  bmr::PhantomLabelFunction            truthAnatomy;
  if (s.truthGeometry == PhantomSettings::TruthGeometryEnum::Anatomy)
  {
    truthAnatomy = AnatomyLabelFunction(s);
  }
  if (IsPelvis(s) && s.tumourFraction > 0.0)
  {
    const TumourBall tumour = TumourBallOf(moving.labels, moving.grid, s);
    AddTumourLabel(s, pair.truthScene);
    truthLabels =
      MakeImageOnGrid<BiomechanicalLabelImageType>(moving.grid, WithTumour(moving.labels, moving.grid, tumour));
    if (truthAnatomy)
    {
      truthAnatomy = [anatomy = truthAnatomy, tumour](double x, double y, double z) {
        const std::int32_t label = anatomy(x, y, z);
        return label == bmr::PelvisProstate && tumour.Contains({ { x, y, z } }) ? PelvisTumour : label;
      };
    }
  }
  // The fixed scan's own grid: the moving one shifted by a sub-voxel offset (fixedGridShiftVoxels), as two scans of
  // a patient are never aligned to the voxel. The truth field and the fixed images live on it.
  const bmr::GridGeometry fixedGrid = ShiftedGrid(moving.grid, s.fixedGridShiftVoxels, 4000 + s.seed);
  const auto              fixedReference =
    MakeImageOnGrid<BiomechanicalLabelImageType>(fixedGrid, std::vector<std::int32_t>(fixedGrid.GetNumberOfVoxels()));
  if (truthMesh.points.empty())
  {
    pipeline::StageClock meshClock(observer, pair.stages);
    truthMesh = truthAnatomy ? MeshTruthAnatomy(truthAnatomy, truthLabels, pair.truthScene, meshClock)
                             : pipeline::MeshLabelImage(truthLabels, pair.truthScene, meshClock, "mesh (CGAL Mesh_3)");
  }
  const SimulationResult truth = SimulateMesh(truthMesh, pair.truthScene, fixedReference, truthLabels, observer, false);
  pair.truthField = truth.pullBack;
  pair.truthTetrahedra = truth.mesh.GetNumberOfTetrahedra();
  pair.truthNodes = truth.mesh.GetNumberOfPoints();
  pair.wallMotionMaxMeanMM = WallMotion(pair.truthScene, truth.mesh);
  pair.stages.insert(pair.stages.end(), truth.stages.begin(), truth.stages.end());

  clock.Begin("warp to the fixed volume");
  pair.fixedCT = WarpImage(pair.movingCT.GetPointer(), truth.pullBack.GetPointer(), false, -1000.0f);
  pair.fixedLabels = FixedLabels(s, fixedGrid, truth.pullBack);
  AddFixedNoise(pair.fixedCT, s);
  clock.End();

  MoveSeeds(pair, moving.seeds, truth.mesh);
  pair.trackedLandmarks = AddTrackingNoise(pair.fixedLandmarks, s.trackingNoiseMM, s.seed);
  AddFixedSubVoxelData(pair, s, clock);
  return pair;
}

PhantomSettings
PhantomSettings::Defaults(AnatomyEnum anatomy)
{
  PhantomSettings s;
  s.anatomy = anatomy;
  if (anatomy == AnatomyEnum::Spheres)
  {
    s.grid = bmr::SpherePhantomParameters().grid;
    s.bladderMM = 1.5;
    s.truthRefineSize = 0.0;
  }
  return s;
}

std::vector<PhantomSettings>
DrawPhantomSet(unsigned int count, std::uint64_t seed, const PhantomSetRanges & ranges)
{
  for (const auto & [name, range] : { std::make_pair("prostate modulus", ranges.prostateE),
                                      std::make_pair("bladder filling", ranges.bladderMM),
                                      std::make_pair("rectum filling", ranges.rectumMM) })
  {
    if (!(std::isfinite(range[0]) && std::isfinite(range[1]) && range[0] > 0.0 && range[0] <= range[1]))
    {
      bmr::FailInput("DrawPhantomSet", std::string("the ") + name + " range must satisfy 0 < low <= high");
    }
  }
  // std::mt19937_64's sequence is fixed by the standard (its distributions are not, so the uniform numbers are
  // made from the raw integers): the same set on every platform.
  std::mt19937_64              rng(seed);
  const auto                   uniform = [&rng](double lo, double hi) { return pipeline::Uniform(rng, lo, hi); };
  std::vector<PhantomSettings> set(count);
  for (unsigned int k = 0; k < count; ++k)
  {
    set[k].prostateE = std::round(std::exp(uniform(std::log(ranges.prostateE[0]), std::log(ranges.prostateE[1]))));
    set[k].bladderMM = std::round(100.0 * uniform(ranges.bladderMM[0], ranges.bladderMM[1])) / 100.0;
    set[k].rectumMM = std::round(100.0 * uniform(ranges.rectumMM[0], ranges.rectumMM[1])) / 100.0;
    set[k].seed = seed * 1000 + k + 1;
  }
  return set;
}

std::ostream &
operator<<(std::ostream & os, PhantomSettings::AnatomyEnum value)
{
  return os << (value == PhantomSettings::AnatomyEnum::Pelvis ? "itk::PhantomSettings::AnatomyEnum::Pelvis"
                                                              : "itk::PhantomSettings::AnatomyEnum::Spheres");
}

} // namespace itk
