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
// biomechreg: physics-based registration of segmented CT from the command line.
//   biomechreg                      demo: pelvis phantom -> estimation of loads and E -> fields -> warped images
//   biomechreg register ...         joint estimation of wall loads and Young's moduli (FEMElasticityOptimizer)
//   biomechreg phantom ...          synthetic moving/fixed pair with ground truth
//   biomechreg simulate ...         forward simulation of a scene on a moving label map
//   biomechreg demons ...           the intensity-based baseline (ITK Demons, multi-resolution)
//   biomechreg phantom-set ...      N phantom pairs with ground-truth seed landmarks
//   biomechreg compare ...          FEM vs Demons vs identity on seed landmarks, with paired t-tests
// Every error is one line on stderr and a non-zero exit; outputs are written to
// temporary names and renamed when complete.
#include "biomechregCommon.h"

#include <algorithm>

namespace {
using namespace bmrcli;

// ----------------------------------------------------------------- phantom

/** Label of the tumour inside the prostate, in the truth's label map only. */
constexpr std::int32_t PelvisTumour = 6;

std::string
Json3(const std::array<double, 3> & p)
{
  std::ostringstream o;
  o << std::setprecision(10) << "[" << p[0] << ", " << p[1] << ", " << p[2] << "]";
  return o.str();
}

bmr::GridGeometry
GridFromArguments(const Arguments & args, const bmr::GridGeometry & defaults)
{
  bmr::GridGeometry     g = defaults;
  std::array<double, 3> size = args.Triple("--size", { { double(g.size[0]), double(g.size[1]), double(g.size[2]) } });
  g.spacing = args.Triple("--spacing", g.spacing);
  for (int i = 0; i < 3; ++i)
  {
    if (!(size[i] >= 1.0 && size[i] <= 4096.0 && size[i] == std::floor(size[i])))
    {
      throw UsageError("--size must be three integers in [1, 4096]");
    }
    g.size[i] = static_cast<std::size_t>(size[i]);
  }
  // Rotation of the grid about the superior (z) axis makes an oblique volume.
  const double a = args.Number("--rotate-z-deg", 0.0) * 3.14159265358979323846 / 180.0;
  g.direction = { std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a), 0, 0, 0, 1 };
  // Centre the grid on the physical origin unless an origin is given.
  std::array<double, 3> half;
  for (int i = 0; i < 3; ++i)
  {
    half[i] = 0.5 * (static_cast<double>(g.size[i]) - 1.0) * g.spacing[i];
  }
  std::array<double, 3> centred;
  for (int r = 0; r < 3; ++r)
  {
    centred[r] = -(g.direction[3 * r] * half[0] + g.direction[3 * r + 1] * half[1] + g.direction[3 * r + 2] * half[2]);
  }
  g.origin = args.Triple("--origin", centred);
  g.Validate("phantom grid (--size/--spacing/--origin)");
  return g;
}

int
PhantomCommand(const Arguments & args)
{
  PhantomOptions o;
  o.scene = args.Get("--scene", "pelvis");
  if (o.scene != "pelvis" && o.scene != "spheres")
  {
    throw UsageError("--scene must be pelvis or spheres");
  }
  o.out = args.Require("--out");
  o.grid = GridFromArguments(
    args, o.scene == "pelvis" ? bmr::PelvisPhantomParameters().grid : bmr::SpherePhantomParameters().grid);
  o.prostateE = args.Number("--true-E-kPa", 50.0);
  o.prostateNu = args.Number("--true-nu", 0.40);
  o.bladderMM = args.Number("--bladder-mm", o.scene == "pelvis" ? 4.0 : 1.5);
  o.rectumMM = args.Number("--rectum-mm", 3.0);
  o.truthRefinement = args.Number("--truth-mesh-scale", 0.75);
  if (!(o.truthRefinement >= 0.3 && o.truthRefinement <= 2.0))
  {
    throw UsageError("--truth-mesh-scale must lie in [0.3, 2] (the truth's mesh sizes relative to the scene's)");
  }
  o.wallLoad = args.Get("--wall-load", "normal");
  if (o.wallLoad != "normal" && o.wallLoad != "point")
  {
    throw UsageError("--wall-load must be normal or point");
  }
  o.tumourFraction = args.Number("--tumour-fraction", 0.0);
  o.tumourE = args.Number("--tumour-E-kPa", 100.0);
  if (!(o.tumourFraction >= 0.0 && o.tumourFraction < 1.0) || !(o.tumourE > 0.0))
  {
    throw UsageError("--tumour-fraction must lie in [0, 1) and --tumour-E-kPa be > 0");
  }
  o.bladderKPa = args.Number("--bladder-kPa", 0.0);
  o.rectumKPa = args.Number("--rectum-kPa", 0.0);
  if (o.bladderKPa < 0.0 || o.rectumKPa < 0.0)
  {
    throw UsageError("--bladder-kPa and --rectum-kPa must be >= 0");
  }
  o.noiseHU = args.Number("--noise-HU", 10.0);
  const double seed = args.Number("--seed", 1.0);
  if (!(seed >= 0.0 && seed == std::floor(seed)))
  {
    throw UsageError("--seed must be a non-negative integer");
  }
  o.seed = static_cast<std::uint64_t>(seed);
  args.CheckAllUsed();
  StageTimer timer;
  std::cout << "biomechreg phantom: " << o.scene << " -> " << o.out << std::endl;
  MakePhantom(o, timer);
  PrintTimings(timer);
  return EXIT_SUCCESS;
}

// ---------------------------------------------------------------- simulate

int
SimulateCommand(const Arguments & args)
{
  const std::string labelsPath = args.Require("--moving-labels");
  const std::string scenePath = args.Require("--scene");
  const std::string out = args.Require("--out");
  const std::string ctPath = args.Get("--moving-ct");
  const std::string referencePath = args.Get("--reference");
  args.CheckAllUsed();

  StageTimer timer;
  std::cout << "biomechreg simulate -> " << out << std::endl;
  timer.Begin("read inputs");
  const bmr::Scene     scene = bmr::ReadScene(scenePath);
  auto                 labels = ReadImage<LabelImageType>(labelsPath, "moving label image");
  CTImageType::Pointer ct;
  if (!ctPath.empty())
  {
    ct = ReadImage<CTImageType>(ctPath, "moving CT");
  }
  itk::ImageBase<3>::ConstPointer reference = labels.GetPointer();
  if (!referencePath.empty())
  {
    reference = ReadImage<CTImageType>(referencePath, "reference image").GetPointer();
  }
  timer.End();
  MakeDirectory(out);
  SimulationOutputs sim = RunSimulation(labels, scene, reference, timer);
  WarpAndWrite(out, sim, labels, ct, timer);
  PrintTimings(timer);
  return EXIT_SUCCESS;
}

// -------------------------------------------------------------------- demo

int
DemoCommand()
{
  const std::string dir = "biomechreg-demo";
  // A stiffness ratio of 10, mid-range of the dissertation's 50-350 kPa (README, estimation benchmark).
  const double trueE = 100.0;
  std::cout << "biomechreg demo: pelvis phantom -> joint estimation of wall loads and prostate modulus -> "
               "displacement fields -> warped images -> report\n"
            << "(outputs in ./" << dir << "; run 'biomechreg help' for the subcommands)\n\n";
  StageTimer     timer;
  PhantomOptions o;
  o.out = dir;
  // 1 mm voxels and a bladder filling of 8 mm: the prostate's shape change is then several voxels of
  // surface motion, which the label maps resolve (at 1.25 x 1.25 x 2.5 mm and 4 mm it is not; see README).
  o.grid = bmr::PelvisPhantomParameters().grid;
  o.grid.size = { { 200, 160, 160 } };
  o.grid.spacing = { { 1.0, 1.0, 1.0 } };
  o.bladderMM = 8.0;
  o.rectumMM = 4.0;
  o.prostateE = trueE;
  std::cout << "1. phantom pair with known truth (prostate " << trueE
            << " kPa, tissue 10 kPa, bladder +8 mm, rectum +4 mm, 1 mm voxels; fixed scan from a finer, "
               "independent mesh)\n";
  MakePhantom(o, timer);

  std::cout << "\n2. registration: the estimator sees the scans, the label maps and scene.json (prostate E unknown)\n";
  RegisterInputs in;
  in.scene = bmr::ReadScene(dir + "/scene.json");
  in.movingLabels = ReadImage<LabelImageType>(dir + "/moving_labels.nrrd", "moving label image");
  in.movingCT = ReadImage<CTImageType>(dir + "/moving_ct.nrrd", "moving CT");
  in.fixedLabels = ReadImage<LabelImageType>(dir + "/fixed_labels.nrrd", "fixed label image");
  in.out = dir + "/register";
  StageTimer           run;
  const RegisterReport report = RunRegistration(in, run);

  const double recovered = report.youngsModulus.at("prostate");
  std::cout << "\n  prostate Young's modulus: true " << std::fixed << std::setprecision(1) << trueE
            << " kPa, recovered " << recovered << " kPa (" << std::showpos << 100.0 * (recovered - trueE) / trueE
            << std::noshowpos << " %)" << UncertaintyText(report, "prostate") << ", gauge soft_tissue 10 kPa"
            << "\n  (the error over 50-350 kPa on this phantom: README, estimation benchmark)"
            << (report.identifiable ? "" : "\n  warning: ") << (report.identifiable ? "" : report.identifiability)
            << "\n  Dice after warping:";
  for (const auto & kv : report.dice)
  {
    std::cout << "  " << kv.first << " " << std::setprecision(4) << kv.second;
  }
  std::cout << "\n  pull-back Jacobian determinant: minimum " << std::setprecision(3) << report.jacobianMinimum
            << ", fraction <= 0: " << report.jacobianNonPositiveFraction << "\n";
  std::cout << "\nPhantom generation:";
  PrintTimings(timer);
  std::cout << "\nRegistration (" << report.tetrahedra << " tetrahedra):";
  PrintTimings(run);
  std::cout << "\nWrote " << dir << "/{moving,fixed}_{ct,labels}.nrrd, scene.json, truth.json, landmarks_*.csv, and "
            << in.out
            << "/{field.nrrd, forward_field.nrrd, warped_ct.nrrd, warped_labels.nrrd, mesh.vtu, history.csv, "
               "sweep.csv, report.json}"
            << std::endl;
  return EXIT_SUCCESS;
}

void
PrintUsage(std::ostream & os)
{
  os
    << "usage:\n"
       "  biomechreg                      run the demo into ./biomechreg-demo\n"
       "  biomechreg phantom --out DIR [--scene pelvis|spheres] [--size NX,NY,NZ] [--spacing SX,SY,SZ mm]\n"
       "                     [--origin X,Y,Z mm] [--rotate-z-deg A] [--true-E-kPa E] [--true-nu NU] [--bladder-mm D]\n"
       "                     [--rectum-mm D] [--wall-load normal|point] [--truth-mesh-scale F]\n"
       "                     [--bladder-kPa P --rectum-kPa P (pressure loads instead)]\n"
       "                     [--tumour-fraction F --tumour-E-kPa E] [--noise-HU S] [--seed N]\n"
       "  biomechreg simulate --moving-labels FILE --scene FILE --out DIR [--moving-ct FILE] [--reference IMAGE]\n"
       "  biomechreg register --moving-ct FILE --moving-labels FILE --fixed-ct FILE --fixed-labels FILE\n"
       "                      --scene FILE --out DIR [--sweep-samples N] [--coarse-factor F] [--mesh-scale F]\n"
       "                      [--wall-spacing-mm D] [--wall-regularization A] [--wall-motion normal|free]\n"
       "                      [--max-outer-iterations N] [--outer-tolerance T] [--element-inversion allow|limit]\n"
       "  biomechreg demons --moving-ct FILE --fixed-ct FILE --out DIR [--moving-labels FILE --fixed-labels FILE\n"
       "                    --flatten LABELS] [--demons-variant diffeomorphic|symmetric] [--demons-levels N]\n"
       "                    [--demons-iterations N (per level)] [--demons-sigma S (voxels)] [--histogram-matching "
       "on|off]\n"
       "  biomechreg phantom-set --out DIR [--count N] [--seed S]\n"
       "  biomechreg compare --pairs LIST.csv --out DIR [--methods identity,fem,demons] [--tag T] [--seed-organ NAME]\n"
       "                     [--flatten LABELS] [register's and demons' settings]\n"
       "Images: NRRD, NIfTI, MetaImage, ... or a DICOM series directory. Units: mm (LPS), kPa, mN.\n";
}
} // namespace

namespace bmrcli {
/** Makes a moving/fixed pair: the fixed images are the moving ones warped by a
 * forward simulation with known moduli on a finer, independently meshed model. */
void
MakePhantom(const PhantomOptions & o, StageTimer & timer)
{
  MakeDirectory(o.out);
  const bool         pelvis = o.scene == "pelvis";
  bmr::PhantomVolume moving;
  timer.Begin("phantom volume");
  std::array<double, 3>        centre;
  bmr::PelvisPhantomParameters pelvisParameters;
  if (pelvis)
  {
    pelvisParameters.grid = o.grid;
    pelvisParameters.seedPlacementSeed = o.seed;
    pelvisParameters.numberOfSeeds = o.numberOfSeeds;
    pelvisParameters.noiseSigmaHU = o.noiseHU;
    pelvisParameters.noiseSeed = 1000 + o.seed;
    moving = bmr::MakePelvisPhantom(pelvisParameters);
  }
  else
  {
    bmr::SpherePhantomParameters p;
    p.grid = o.grid;
    moving = bmr::MakeSpherePhantom(p);
    bmr::AddGaussianNoise(moving.ct, o.noiseHU, 1000 + o.seed);
  }
  centre = bmr::GridCenter(moving.grid);
  timer.End();

  // Truth: known moduli and wall displacements, on a finer mesh with another random seed.
  bmr::Scene truth = ScaledMeshSizes(
    pelvis ? PelvisScene(o.prostateE, false, o.prostateNu) : SpheresScene(o.prostateE, false), o.truthRefinement);
  truth.mesh.randomSeed = 12345;
  if (pelvis && (o.bladderKPa > 0.0 || o.rectumKPa > 0.0))
  {
    // Pressure in the lumens: the walls move as the tissue lets them (no wall is driven into the prostate).
    truth.loads = { { "bladder", bmr::SceneLoad::Type::Pressure, { { 0, 0, 0 } }, o.bladderKPa },
                    { "rectum", bmr::SceneLoad::Type::Pressure, { { 0, 0, 0 } }, o.rectumKPa } };
  }
  else if (pelvis)
  {
    truth.loads = {
      { "bladder",
        bmr::SceneLoad::Type::RadialDisplacement,
        { { centre[0], centre[1] - 5, centre[2] + 30 } },
        o.bladderMM },
      { "rectum", bmr::SceneLoad::Type::RadialDisplacement, { { centre[0], centre[1] + 38, centre[2] } }, o.rectumMM }
    };
    if (o.wallLoad == "normal")
    {
      // Filling moves each wall along its own normals: the bladder along those of its ellipsoid
      // (semi-axes as in bmrPhantom.cxx), the rectum radially from its axis and from the centre of its
      // dome. The "point" loads (radial from one point each) also slide the walls along themselves, the
      // rectal wall next to the prostate by up to 0.8 |d| along its axis: motion that no segmentation
      // shows and that the estimate absorbs into E (README, "What the walls do to the estimate").
      truth.loads[0].semiAxes = { { 34, 28, 24 } };
      truth.loads[1].center = { { centre[0], centre[1] + 38, centre[2] + 15 } };
      truth.loads[1].axis = { { 0, 0, 1 } };
    }
  }
  else
  {
    truth.loads = { { "outside", bmr::SceneLoad::Type::RadialDisplacement, centre, -o.bladderMM } };
  }
  truth.Validate();

  auto movingCT = itk::MakeImageOnGrid<CTImageType>(moving.grid, moving.ct);
  auto movingLabels = itk::MakeImageOnGrid<LabelImageType>(moving.grid, moving.labels);
  // The truth may hold a stiffer tumour inside the prostate (dissertation Table 3.4): a ball at the
  // prostate's centroid with the requested fraction of its volume, labelled only in the truth's label map.
  // The estimator sees one homogeneous prostate.
  LabelImageType::Pointer truthLabels = movingLabels;
  if (pelvis && o.tumourFraction > 0.0)
  {
    std::vector<std::int32_t> labels = moving.labels;
    std::array<double, 3>     c{ { 0, 0, 0 } };
    std::size_t               n = 0;
    const auto &              g = moving.grid;
    const auto                at = [&g](std::size_t v) {
      return g.IndexToPoint(
        { { double(v % g.size[0]), double((v / g.size[0]) % g.size[1]), double(v / (g.size[0] * g.size[1])) } });
    };
    for (std::size_t v = 0; v < labels.size(); ++v)
    {
      if (labels[v] == bmr::PelvisProstate)
      {
        const auto x = at(v);
        for (int a = 0; a < 3; ++a)
        {
          c[a] += x[a];
        }
        ++n;
      }
    }
    const double voxel = g.spacing[0] * g.spacing[1] * g.spacing[2];
    const double r = std::cbrt(o.tumourFraction * double(n) * voxel * 3.0 / (4.0 * 3.14159265358979));
    for (int a = 0; a < 3; ++a)
    {
      c[a] /= double(std::max<std::size_t>(n, 1));
    }
    for (std::size_t v = 0; v < labels.size(); ++v)
    {
      const auto x = at(v);
      if (labels[v] == bmr::PelvisProstate && std::hypot(x[0] - c[0], x[1] - c[1], x[2] - c[2]) <= r)
      {
        labels[v] = PelvisTumour;
      }
    }
    truthLabels = itk::MakeImageOnGrid<LabelImageType>(moving.grid, labels);
    truth.labels.push_back({ "tumour", PelvisTumour, bmr::LabelRole::Material, o.tumourE, o.prostateNu });
    truth.mesh.cellSizePerLabel[PelvisTumour] = truth.mesh.cellSizePerLabel[bmr::PelvisProstate];
  }
  SimulationOutputs sim = RunSimulation(truthLabels, truth, movingLabels, timer);

  timer.Begin("warp to the fixed volume");
  auto fixedCT = Warp<CTImageType>(movingCT, sim.pullBack, false, -1000.0f);
  // Pelvis: the fixed labels voxelise the deformed analytic anatomy once (the label at each voxel's
  // pull-back point), as a scan would; resampling the voxelised moving labels would quantise twice.
  LabelImageType::Pointer fixedLabels;
  if (pelvis)
  {
    std::vector<double> points(3 * moving.grid.GetNumberOfVoxels());
    const auto *        d = sim.pullBack->GetBufferPointer();
    for (std::size_t v = 0; v < moving.grid.GetNumberOfVoxels(); ++v)
    {
      const auto x = moving.grid.IndexToPoint({ { double(v % moving.grid.size[0]),
                                                  double((v / moving.grid.size[0]) % moving.grid.size[1]),
                                                  double(v / (moving.grid.size[0] * moving.grid.size[1])) } });
      for (int c = 0; c < 3; ++c)
      {
        points[3 * v + c] = x[c] + d[v][c];
      }
    }
    fixedLabels = itk::MakeImageOnGrid<LabelImageType>(moving.grid, bmr::PelvisLabelsAt(pelvisParameters, points));
  }
  else
  {
    fixedLabels = Warp<LabelImageType>(movingLabels, sim.pullBack, true, 0);
  }
  // The fixed scan has its own noise on top of the warped (noisy) moving one.
  {
    std::vector<float> noise(fixedCT->GetBufferedRegion().GetNumberOfPixels(), 0.0f);
    bmr::AddGaussianNoise(noise, o.noiseHU, 2000 + o.seed);
    float * p = fixedCT->GetBufferPointer();
    for (std::size_t i = 0; i < noise.size(); ++i)
    {
      p[i] += noise[i];
    }
  }
  timer.End();

  // Ground-truth landmarks: seed centres moved by the simulated displacement.
  const bmr::PointLocator locator(sim.mesh.points, sim.mesh.tetrahedra);
  std::ostringstream      movingCsv, fixedCsv, landmarksJson;
  movingCsv << "# implanted seed centres, LPS physical coordinates [mm]\nid,x_mm,y_mm,z_mm\n";
  fixedCsv << movingCsv.str();
  movingCsv << std::setprecision(10);
  fixedCsv << std::setprecision(10);
  for (std::size_t i = 0; i < moving.seeds.size(); ++i)
  {
    const auto &          X = moving.seeds[i].center;
    std::array<double, 3> u;
    if (!bmr::InterpolateDisplacement(locator, sim.mesh, sim.mesh.displacement, X, u))
    {
      throw std::runtime_error("seed " + std::to_string(i) + " lies outside the simulated mesh");
    }
    const std::array<double, 3> x{ { X[0] + u[0], X[1] + u[1], X[2] + u[2] } };
    movingCsv << "seed" << i << "," << X[0] << "," << X[1] << "," << X[2] << "\n";
    fixedCsv << "seed" << i << "," << x[0] << "," << x[1] << "," << x[2] << "\n";
    landmarksJson << (i ? ",\n" : "") << "    {\"id\": \"seed" << i << "\", \"moving_mm\": " << Json3(X)
                  << ", \"fixed_mm\": " << Json3(x) << "}";
  }

  timer.Begin("write outputs");
  WriteImage<CTImageType>(movingCT, o.out + "/moving_ct.nrrd");
  WriteImage<LabelImageType>(movingLabels, o.out + "/moving_labels.nrrd");
  WriteImage<CTImageType>(fixedCT, o.out + "/fixed_ct.nrrd");
  WriteImage<LabelImageType>(fixedLabels, o.out + "/fixed_labels.nrrd");
  WriteImage<FieldType>(sim.pullBack, o.out + "/truth_field.nrrd");
  bmr::Scene estimation = pelvis ? PelvisScene(50.0, true) : SpheresScene(50.0, true);
  estimation.movingLandmarks = "landmarks_moving.csv";
  estimation.fixedLandmarks = "landmarks_fixed.csv";
  if (moving.seeds.empty())
  {
    estimation.movingLandmarks.clear();
    estimation.fixedLandmarks.clear();
  }
  bmr::WriteTextFileAtomically(o.out + "/scene.json", bmr::SceneToJson(estimation));
  bmr::WriteTextFileAtomically(o.out + "/truth_scene.json", bmr::SceneToJson(truth));
  if (!moving.seeds.empty())
  {
    bmr::WriteTextFileAtomically(o.out + "/landmarks_moving.csv", movingCsv.str());
    bmr::WriteTextFileAtomically(o.out + "/landmarks_fixed.csv", fixedCsv.str());
  }
  std::ostringstream t;
  t << std::setprecision(10) << "{\n  \"units\": {\"length\": \"mm\", \"modulus\": \"kPa\", \"force\": \"mN\"},\n"
    << "  \"scene\": \"" << o.scene << "\",\n  \"youngs_modulus_kPa\": {";
  bool first = true;
  for (const auto & l : truth.labels)
  {
    if (l.role == bmr::LabelRole::Material)
    {
      t << (first ? "" : ", ") << "\"" << l.name << "\": " << l.youngsModulus;
      first = false;
    }
  }
  t << "},\n  \"poisson_ratio\": {";
  first = true;
  for (const auto & l : truth.labels)
  {
    if (l.role == bmr::LabelRole::Material)
    {
      t << (first ? "" : ", ") << "\"" << l.name << "\": " << l.poissonRatio;
      first = false;
    }
  }
  t << "},\n  \"tumour_volume_fraction\": " << (pelvis ? o.tumourFraction : 0.0) << ",\n  \"wall_loads\": [";
  for (std::size_t i = 0; i < truth.loads.size(); ++i)
  {
    const bmr::SceneLoad & l = truth.loads[i];
    t << (i ? ", " : "") << "{\"surface\": \"" << l.surface << "\", ";
    if (l.type == bmr::SceneLoad::Type::Pressure)
    {
      t << "\"type\": \"pressure\", \"pressure_kPa\": " << l.magnitude << "}";
    }
    else
    {
      t << "\"type\": \"radial_displacement\", \"center_mm\": " << Json3(l.center);
      if (l.axis != std::array<double, 3>{ { 0, 0, 0 } })
      {
        t << ", \"axis\": " << Json3(l.axis);
      }
      if (l.semiAxes != std::array<double, 3>{ { 0, 0, 0 } })
      {
        t << ", \"semi_axes_mm\": " << Json3(l.semiAxes);
      }
      t << ", \"magnitude_mm\": " << l.magnitude << "}";
    }
  }
  t << "],\n  \"truth_mesh\": {\"tetrahedra\": " << sim.mesh.GetNumberOfTetrahedra()
    << ", \"nodes\": " << sim.mesh.GetNumberOfPoints() << ", \"cell_size_mm\": " << truth.mesh.cellSize
    << "},\n  \"ct_noise_sigma_HU\": " << o.noiseHU << ",\n  \"landmarks\": [\n"
    << landmarksJson.str() << "\n  ]\n}\n";
  bmr::WriteTextFileAtomically(o.out + "/truth.json", t.str());
  timer.End();
}

} // namespace bmrcli

int
main(int argc, char * argv[])
{
  try
  {
    if (argc < 2)
    {
      return DemoCommand();
    }
    const std::string command = argv[1];
    if (command == "help" || command == "--help" || command == "-h")
    {
      PrintUsage(std::cout);
      return EXIT_SUCCESS;
    }
    const Arguments args(argc, argv, 2);
    if (command == "phantom")
    {
      return PhantomCommand(args);
    }
    if (command == "simulate")
    {
      return SimulateCommand(args);
    }
    if (command == "register")
    {
      return RegisterCommand(args);
    }
    if (command == "demons")
    {
      return bmrcli::DemonsCommand(args);
    }
    if (command == "compare")
    {
      return bmrcli::CompareCommand(args);
    }
    if (command == "phantom-set")
    {
      return bmrcli::PhantomSetCommand(args);
    }
    throw UsageError("unknown command \"" + command + "\" (try: biomechreg help)");
  }
  catch (const UsageError & e)
  {
    std::cerr << "biomechreg: error: " << e.what() << " (see biomechreg help)" << std::endl;
    return 2;
  }
  catch (const itk::ExceptionObject & e)
  {
    std::string d = e.GetDescription();
    std::replace(d.begin(), d.end(), '\n', ' ');
    std::cerr << "biomechreg: error: " << d << std::endl;
    return 1;
  }
  catch (const std::exception & e)
  {
    std::cerr << "biomechreg: error: " << e.what() << std::endl;
    return 1;
  }
}
