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
//   biomechreg phantom-cohort ...   N phantom patients x M fractions with their truth (stage, modulus, anatomy)
//   biomechreg cohort ...           the cohort workflow on Snakemake: one registration per daily image, statistics
//   biomechreg cohort-stats ...     the statistics of a cohort's registrations (the workflow's last step)
//   biomechreg markers ...          the treatment anatomy from tracked markers (FEM vs rigid vs spline)
//   biomechreg dose ...             per-organ DVHs, D95/D2/Dmean, V-doses and gEUD of a dose or a synthetic plan
//   biomechreg rt-export ...        a label map as a DICOM RTSTRUCT, a dose as an RTDOSE (for a planning system)
//   biomechreg help [SUB], biomechreg SUB --help, biomechreg --version
// Every error is one line on stderr and a non-zero exit (2 for usage errors, 1 otherwise); outputs are
// written to temporary names and renamed when complete.
#include "biomechregCommon.h"
#include "biomechregSlicer.h"
#include "bmrTaskTrace.h"
#include "itkBiomechanicalReports.h"
#include "itkMultiThreaderBase.h"
#include "itkVersion.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <future>
#include <map>
#include <memory>

namespace {
using namespace bmrcli;

// ----------------------------------------------------------------- phantom

itk::PhantomSettings
ParsePhantomSettings(const Arguments & args)
{
  const bool           pelvis = args.Choice("--scene", { "pelvis", "spheres" }) == "pelvis";
  itk::PhantomSettings o = itk::PhantomSettings::Defaults(pelvis ? itk::PhantomSettings::AnatomyEnum::Pelvis
                                                                 : itk::PhantomSettings::AnatomyEnum::Spheres);
  o.grid = GridFromArguments(args, o.grid);
  o.prostateE = args.Number("--true-E-kPa", o.prostateE);
  o.prostateNu = args.Number("--true-nu", o.prostateNu);
  o.tissueE = args.Number("--tissue-E-kPa", o.tissueE);
  if (!(o.tissueE > 0.0))
  {
    throw UsageError("--tissue-E-kPa must be > 0 (the truth's soft tissue; the estimation scene assumes 10 kPa)");
  }
  o.bladderMM = args.Number("--bladder-mm", o.bladderMM);
  o.rectumMM = args.Number("--rectum-mm", o.rectumMM);
  o.fractions = args.Choice("--fractions", { "off", "on" }) == "on";
  o.contourFractions = args.Choice("--outline-fractions", { "off", "on" }) == "on";
  o.model = args.Choice("--model", { "linear", "neo_hookean" }) == "neo_hookean" ? bmr::MaterialModelEnum::NeoHookean
                                                                                 : bmr::MaterialModelEnum::Linear;
  o.truthRefinement = args.Number("--truth-mesh-scale", o.truthRefinement);
  if (!(o.truthRefinement >= 0.3 && o.truthRefinement <= 2.0))
  {
    throw UsageError("--truth-mesh-scale must lie in [0.3, 2] (the truth's mesh sizes relative to the scene's)");
  }
  o.truthGeometry = args.Choice("--truth-geometry", { "anatomy", "voxels" }) == "anatomy"
                      ? itk::PhantomSettings::TruthGeometryEnum::Anatomy
                      : itk::PhantomSettings::TruthGeometryEnum::Voxels;
  o.truthRefineSize = args.Number("--truth-refine-size-mm", o.truthRefineSize);
  o.truthRefineDistance = args.Number("--truth-refine-distance-mm", o.truthRefineDistance);
  if (!(o.truthRefineSize >= 0.0) || !(o.truthRefineDistance >= 0.0))
  {
    throw UsageError("--truth-refine-size-mm and --truth-refine-distance-mm must be >= 0");
  }
  o.fixedGridShiftVoxels = args.Number("--fixed-grid-shift-voxels", o.fixedGridShiftVoxels);
  if (!(o.fixedGridShiftVoxels >= 0.0 && o.fixedGridShiftVoxels <= 0.5))
  {
    throw UsageError("--fixed-grid-shift-voxels must lie in [0, 0.5] (the fixed grid's offset, U(-S, S) voxels)");
  }
  o.filling = args.Choice("--wall-load", { "normal", "point" }) == "normal" ? bmr::WallFillingEnum::AlongNormals
                                                                            : bmr::WallFillingEnum::FromPoint;
  o.tumourFraction = args.Number("--tumour-fraction", o.tumourFraction);
  o.tumourE = args.Number("--tumour-E-kPa", o.tumourE);
  if (!(o.tumourFraction >= 0.0 && o.tumourFraction < 1.0) || !(o.tumourE > 0.0))
  {
    throw UsageError("--tumour-fraction must lie in [0, 1) and --tumour-E-kPa be > 0");
  }
  o.bladderKPa = args.Number("--bladder-kPa", o.bladderKPa);
  o.rectumKPa = args.Number("--rectum-kPa", o.rectumKPa);
  if (o.bladderKPa < 0.0 || o.rectumKPa < 0.0)
  {
    throw UsageError("--bladder-kPa and --rectum-kPa must be >= 0");
  }
  o.noiseHU = args.Number("--noise-HU", o.noiseHU);
  o.trackingNoiseMM = args.Number("--tracking-noise-mm", o.trackingNoiseMM);
  if (!(o.trackingNoiseMM >= 0.0 && o.trackingNoiseMM <= 10.0))
  {
    throw UsageError("--tracking-noise-mm must lie in [0, 10]");
  }
  const double seed = args.Number("--seed", 1.0);
  if (!(seed >= 0.0 && seed == std::floor(seed)))
  {
    throw UsageError("--seed must be a non-negative integer");
  }
  o.seed = static_cast<std::uint64_t>(seed);
  return o;
}

int
PhantomCommand(const Arguments & args)
{
  const std::string out = args.Require("--out");
  const auto        settings = ParsePhantomSettings(args);
  args.CheckAllUsed();
  StageTimer timer;
  std::cout << "biomechreg phantom: "
            << (settings.anatomy == itk::PhantomSettings::AnatomyEnum::Pelvis ? "pelvis" : "spheres") << " -> " << out
            << std::endl;
  const itk::PhantomPair pair = itk::MakePhantomPair(settings, &timer);
  WritePhantom(out, pair, settings, timer);
  Stages all = pair.stages;
  all.insert(all.end(), timer.stages.begin(), timer.stages.end());
  PrintTimings(all);
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
  const bmr::Scene                scene = bmr::ReadScene(scenePath);
  auto                            labels = ReadImage<LabelImageType>(labelsPath, "moving label image");
  CTImageType::Pointer            ct = ctPath.empty() ? nullptr : ReadImage<CTImageType>(ctPath, "moving CT");
  itk::ImageBase<3>::ConstPointer reference = labels.GetPointer();
  if (!referencePath.empty())
  {
    reference = ReadImage<CTImageType>(referencePath, "reference image").GetPointer();
  }
  timer.End();
  const itk::SimulationResult sim = itk::SimulateLabelImage(labels, scene, reference, &timer);
  timer.stages.insert(timer.stages.end(), sim.stages.begin(), sim.stages.end());
  timer.Begin("warp (CT linear; labels nearest)");
  const auto warpedLabels = itk::WarpImage(labels.GetPointer(), sim.pullBack.GetPointer(), true, 0);
  const auto warpedCT = ct ? itk::WarpImage(ct.GetPointer(), sim.pullBack.GetPointer(), false, -1000.0f) : nullptr;
  timer.End();
  timer.Begin("write outputs");
  itk::WriteSimulationOutputs(out, sim, warpedLabels, warpedCT);
  timer.End();
  PrintTimings(timer.stages);
  return EXIT_SUCCESS;
}

// -------------------------------------------------------------------- demo

/** "<tetrahedra> tetrahedra, <n> resample meshes, <s> s of meshing": what MeshMovingAnatomy() made. */
std::string
MeshedAlongsideDetail(const itk::MovingAnatomyMeshes & meshes)
{
  double seconds = 0.0;
  for (const auto & stage : meshes.stages)
  {
    seconds += stage.seconds;
  }
  std::ostringstream detail;
  detail << meshes.fine.GetNumberOfTetrahedra() << " tetrahedra, " << meshes.resamples.size() << " resample meshes, "
         << std::fixed << std::setprecision(1) << seconds << " s of meshing";
  return detail.str();
}

/** The demo's phantom: the pelvis with a prostate of \a trueE [kPa]. */
itk::PhantomSettings
DemoPhantomSettings(double trueE)
{
  // 1 mm voxels and a bladder filling of 8 mm: the prostate's shape change is then several voxels of
  // surface motion, which the label maps resolve (at 1.25 x 1.25 x 2.5 mm and 4 mm it is not; README).
  itk::PhantomSettings o;
  o.grid.size = { { 200, 160, 160 } };
  o.grid.spacing = { { 1.0, 1.0, 1.0 } };
  o.bladderMM = 8.0;
  o.rectumMM = 4.0;
  o.prostateE = trueE;
  return o;
}

/** The prostate's modulus recovered against the truth \a trueE [kPa], Dice after warping and the Jacobian. */
void
PrintDemoEstimate(const itk::RegistrationResult & result, double trueE)
{
  const auto   stated = result.modulusInterval.find("prostate");
  const double recovered =
    stated == result.modulusInterval.end() ? result.youngsModulus.at("prostate") : stated->second.estimate;
  std::cout << "\n  prostate Young's modulus: true " << std::fixed << std::setprecision(1) << trueE
            << " kPa, recovered " << recovered << " kPa (" << std::showpos << 100.0 * (recovered - trueE) / trueE
            << std::noshowpos << " %), fit " << result.youngsModulus.at("prostate") << " kPa"
            << itk::UncertaintyText(result, "prostate") << ", gauge soft_tissue 10 kPa"
            << "\n  (coverage of the interval over 30-500 kPa: docs/results.md)"
            << "\n  note: " << itk::WallLawCaveat(itk::RegistrationSettings().walls)
            << (result.estimation.identifiable ? "" : "\n  warning: ")
            << (result.estimation.identifiable ? "" : result.estimation.identifiabilityMessage)
            << "\n  Dice after warping:";
  for (const auto & kv : result.dice)
  {
    std::cout << "  " << kv.first << " " << std::setprecision(4) << kv.second;
  }
  std::cout << "\n  pull-back Jacobian determinant: minimum " << std::setprecision(3) << result.jacobianMinimum
            << ", fraction <= 0: " << result.jacobianNonPositiveFraction << "\n";
}

int
DemoCommand()
{
  const std::string dir = "biomechreg-demo";
  // A stiffness ratio of 10, mid-range of the dissertation's 50-350 kPa (docs/history/benchmarks.md).
  const double trueE = 100.0;
  std::cout << "biomechreg demo: pelvis phantom -> joint estimation of wall loads and prostate modulus -> "
               "displacement fields -> warped images -> report\n"
            << "(outputs in ./" << dir << "; run 'biomechreg help' for the subcommands)\n\n";
  const itk::PhantomSettings o = DemoPhantomSettings(trueE);
  std::cout << "1. phantom pair with known truth (prostate " << trueE
            << " kPa, tissue 10 kPa, bladder +8 mm, rectum +4 mm, 1 mm voxels; fixed scan from a finer, "
               "independent mesh)\n";
  StageTimer timer;
  // The truth's meshing and factorization run on one core: the registration's meshes of the moving anatomy (its
  // fit, sweep and resamples) are made on the other meanwhile, as a planning scan's would be before the daily scan.
  itk::RegistrationSettings             settings;
  std::future<itk::MovingAnatomyMeshes> meshes;
  bmr::TetrahedralMesh                  truthMesh;
  const itk::PhantomPair                pair = itk::MakePhantomPair(
    o, &timer, truthMesh, [&](const itk::BiomechanicalLabelImageType * labels, const bmr::Scene & scene) {
      // The image is held here: should the phantom fail, its pair is gone before this thread is waited for.
      const itk::BiomechanicalLabelImageType::ConstPointer held(labels);
      // On one thread (--threads 1) they are made when the registration asks for them.
      const auto policy =
        itk::MultiThreaderBase::GetGlobalDefaultNumberOfThreads() > 1 ? std::launch::async : std::launch::deferred;
      meshes = std::async(
        policy, [held, scene, &settings]() { return itk::MeshMovingAnatomy(held.GetPointer(), scene, settings); });
    });
  WritePhantom(dir, pair, o, timer);

  std::cout << "\n2. registration: the estimator sees the scans, the label maps and scene.json (prostate E unknown)\n";
  StageTimer run(true);
  run.Begin("moving anatomy meshed alongside the phantom (the wait)");
  const itk::MovingAnatomyMeshes premeshed = meshes.get();
  run.End(MeshedAlongsideDetail(premeshed));
  settings.meshes = &premeshed;
  const auto result =
    itk::RegisterSegmentedPair(pair.movingLabels, pair.fixedLabels, pair.movingCT, pair.scene, settings, &run);
  run.stages.insert(run.stages.end(), result.state.stages.begin(), result.state.stages.end());
  // The demo's plot (scripts/plot_register.py) reads the sweep and the convergence history.
  itk::RegistrationOutputs outputs;
  outputs.history = outputs.sweep = true;
  WriteRegistration(dir + "/register", result, settings, outputs, run);
  PrintOuterIterations(result);

  PrintDemoEstimate(result, trueE);
  Stages phantomStages = pair.stages;
  phantomStages.insert(phantomStages.end(), timer.stages.begin(), timer.stages.end());
  std::cout << "\nPhantom generation:";
  PrintTimings(phantomStages);
  std::cout << "\nRegistration (" << result.state.mesh.GetNumberOfTetrahedra() << " tetrahedra):";
  PrintTimings(run.stages);
  std::cout << "\nWrote " << dir << "/{moving,fixed}_{ct,labels}.nrrd, scene.json, truth.json, landmarks_*.csv, and "
            << dir << "/register/{field.nrrd, warped_ct.nrrd, warped_labels.nrrd, report.json, history.csv, sweep.csv}"
            << std::endl;
  return EXIT_SUCCESS;
}

} // namespace

namespace bmrcli {
int
DoseCommand(const Arguments & args); // biomechregDose.cxx
int
MarkersCommand(const Arguments & args); // biomechregMarkers.cxx
int
RTExportCommand(const Arguments & args); // biomechregRTExport.cxx
int
TrainBasisCommand(const Arguments & args); // biomechregTrainBasis.cxx

void
WritePhantom(const std::string &          out,
             const itk::PhantomPair &     pair,
             const itk::PhantomSettings & settings,
             StageTimer &                 timer)
{
  timer.Begin("write outputs");
  itk::WritePhantomPair(out, pair, settings);
  timer.End();
}
} // namespace bmrcli

namespace bmrcli {

/** The version line, and under --verbose which malloc the program runs on. */
void
PrintVersion()
{
  std::cout << "biomechreg " << BMR_VERSION << " (ITKBiomechanicalRegistration; ITK " << itk::Version::GetITKVersion()
            << ")" << std::endl;
  if (GetVerbosity() == Verbosity::Verbose)
  {
    std::cout << "malloc: " << MallocDescription() << std::endl;
  }
}

/** Runs subcommand \a command (not the demo, help or version) with its \a options; its exit status. */
int
RunSubcommand(const std::string & command, const Arguments & options)
{
  using Handler = std::function<int(const Arguments &)>;
  static const std::map<std::string, Handler> handlers = {
    { "phantom", PhantomCommand },
    { "simulate", SimulateCommand },
    { "register", RegisterCommand },
    { "demons", bmrcli::DemonsCommand },
    { "warp", bmrcli::WarpCommand },
    { "compare", bmrcli::CompareCommand },
    { "phantom-set", bmrcli::PhantomSetCommand },
    { "phantom-cohort", bmrcli::PhantomCohortCommand },
    { "cohort",
      [](const Arguments & a) {
        return bmrcli::CohortCommand(a, std::filesystem::canonical("/proc/self/exe").string());
      } },
    { "cohort-stats", bmrcli::CohortStatsCommand },
    { "dose", bmrcli::DoseCommand },
    { "markers", bmrcli::MarkersCommand },
    { "rt-export", bmrcli::RTExportCommand },
    { "train-basis", bmrcli::TrainBasisCommand }
  };
  const auto found = handlers.find(command);
  if (found == handlers.end())
  {
    throw UsageError("unknown command \"" + command + "\"");
  }
  return found->second(options);
}

/** Records the parallel work (bmr::TaskTrace) into \a path, when given, until the command returns. */
class TaskTraceFile
{
public:
  explicit TaskTraceFile(std::string path)
    : m_Path(std::move(path))
    , m_Trace(m_Path.empty() ? nullptr : std::make_unique<bmr::TaskTrace>())
  {}
  ~TaskTraceFile()
  {
    try
    {
      if (m_Trace)
      {
        m_Trace->Write(m_Path);
      }
    }
    catch (const std::exception & e)
    {
      std::cerr << "biomechreg: error: " << e.what() << std::endl;
    }
  }
  TaskTraceFile(const TaskTraceFile &) = delete;
  TaskTraceFile &
  operator=(const TaskTraceFile &) = delete;

private:
  std::string                     m_Path;
  std::unique_ptr<bmr::TaskTrace> m_Trace;
};
} // namespace bmrcli

int
main(int argc, char * argv[])
{
  // Run as a 3D Slicer module (a link named after it), biomechreg speaks Slicer's protocol instead.
  const bmrcli::SlicerModule * slicer = bmrcli::FindSlicerModule(argv[0]);
  try
  {
    std::vector<std::string> args(argv + 1, argv + argc);
    if (slicer != nullptr)
    {
      return bmrcli::RunSlicerModule(*slicer, args, bmrcli::RunSubcommand);
    }
    const GlobalOptions global = TakeGlobalOptions(args);
    ApplyGlobalOptions(global);
    const TaskTraceFile trace(global.taskTrace);
    const std::string   command = args.empty() ? std::string() : args.front();
    if (global.version || command == "version")
    {
      PrintVersion();
      return EXIT_SUCCESS;
    }
    if (command == "help" || global.help)
    {
      // "biomechreg help SUB", "biomechreg SUB --help": that subcommand's usage; otherwise all of them.
      const std::string topic = command == "help" ? (args.size() > 1 ? args[1] : std::string()) : command;
      if (!topic.empty() && !IsCommand(topic))
      {
        throw UsageError("unknown command \"" + topic + "\"");
      }
      PrintUsage(std::cout, topic);
      return EXIT_SUCCESS;
    }
    if (command.empty())
    {
      return DemoCommand();
    }
    return RunSubcommand(command, Arguments(std::vector<std::string>(args.begin() + 1, args.end())));
  }
  catch (const UsageError & e)
  {
    bmrcli::EndStageLineOnError();
    std::cerr << "biomechreg: error: " << e.what() << " (see biomechreg help)" << std::endl;
    return 2;
  }
  catch (const itk::ExceptionObject & e)
  {
    std::string d = e.GetDescription();
    std::replace(d.begin(), d.end(), '\n', ' ');
    bmrcli::EndStageLineOnError();
    std::cerr << "biomechreg: error: " << d << std::endl;
    return 1;
  }
  catch (const std::exception & e)
  {
    bmrcli::EndStageLineOnError();
    std::cerr << "biomechreg: error: " << e.what() << std::endl;
    return 1;
  }
}
