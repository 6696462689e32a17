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
// biomechreg register: joint estimation of boundary loads and elasticity
// (FEMElasticityOptimizer) and the displacement fields, warped images and
// report that come out of it.
#include "biomechregCommon.h"
#include "itkRegistrationQualityMeasures.h"
#include "itkFEMElasticityOptimizer.h"
#include "itkSceneDistanceMaps.h"

#include "itkCommand.h"

#include <algorithm>
#include <fstream>
#include <limits>

namespace bmrcli {
namespace {

/** Prints one line per inner solve (the optimizer's IterationEvent). */
class ProgressPrinter : public itk::Command
{
public:
  using Self = ProgressPrinter;
  using Pointer = itk::SmartPointer<Self>;
  itkNewMacro(Self);
  void
  Execute(itk::Object * caller, const itk::EventObject & event) override
  {
    Execute(static_cast<const itk::Object *>(caller), event);
  }
  void
  Execute(const itk::Object * caller, const itk::EventObject & event) override
  {
    if (!itk::IterationEvent().CheckEvent(&event))
    {
      return;
    }
    const auto & r = static_cast<const itk::FEMElasticityOptimizer *>(caller)->GetCurrentRecord();
    std::cout << "    " << std::left << std::setw(6) << r.stage << std::right << std::setw(3) << r.iteration;
    for (double E : r.youngsModuli)
    {
      std::cout << "  E " << std::fixed << std::setprecision(2) << std::setw(8) << E << " kPa";
    }
    std::cout << "  Phi* " << std::scientific << std::setprecision(5) << r.value << " mm^2";
    for (double g : r.logModulusGradient)
    {
      std::cout << "  dPhi/dlogE " << std::setprecision(2) << std::setw(9) << g;
    }
    std::cout << "  |dPhi/dd| " << std::setprecision(1) << r.wallGradientNorm << "  inner " << std::setw(4)
              << r.innerIterations << "  " << std::fixed << std::setprecision(2) << r.seconds << " s" << std::endl;
  }

protected:
  ProgressPrinter() = default;
};

std::string
HistoryCsv(const std::vector<itk::FEMElasticityOptimizer::IterationRecord> & records,
           const std::vector<std::string> &                                  unknownNames)
{
  std::ostringstream o;
  o << "# Phi* [mm^2] at the inner optimum; |dPhi/dd| [mm]; dPhi/dlogE [mm^2]; E [kPa]\nstage,iteration";
  for (const auto & n : unknownNames)
  {
    o << ",E_" << n << "_kPa";
  }
  o << ",phi_mm2,wall_gradient_norm_mm";
  for (const auto & n : unknownNames)
  {
    o << ",dphi_dlogE_" << n << "_mm2";
  }
  o << ",inner_iterations,seconds\n" << std::setprecision(10);
  for (const auto & r : records)
  {
    o << r.stage << "," << r.iteration;
    for (double E : r.youngsModuli)
    {
      o << "," << E;
    }
    o << "," << r.value << "," << r.wallGradientNorm;
    for (double g : r.logModulusGradient)
    {
      o << "," << g;
    }
    o << "," << r.innerIterations << "," << r.seconds << "\n";
  }
  return o.str();
}

std::string
JsonString(const std::string & s)
{
  std::string o = "\"";
  for (char c : s)
  {
    if (c == '"' || c == '\\')
    {
      o += '\\';
    }
    o += c;
  }
  return o + "\"";
}

/** A number for JSON, which has no infinity: null when not finite. */
std::string
JsonNumber(double x)
{
  if (!std::isfinite(x))
  {
    return "null";
  }
  std::ostringstream o;
  o << std::setprecision(8) << x;
  return o.str();
}

// Standard deviation of log E above which register warns: one sigma beyond the 10 % the estimate aims at.
constexpr double kUncertaintyWarningLogSigma = 0.1;
} // namespace

/** Axis-aligned physical bounding box [mm] of an image's voxel box (the corners at +-half a voxel). */
std::array<std::array<double, 2>, 3>
PhysicalBounds(const itk::ImageBase<3> * image)
{
  std::array<std::array<double, 2>, 3> b;
  for (auto & axis : b)
  {
    axis = { { std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity() } };
  }
  const auto region = image->GetLargestPossibleRegion();
  for (int corner = 0; corner < 8; ++corner)
  {
    itk::ContinuousIndex<double, 3> index;
    for (unsigned int a = 0; a < 3; ++a)
    {
      index[a] = region.GetIndex(a) - 0.5 + ((corner >> a) & 1 ? double(region.GetSize(a)) : 0.0);
    }
    itk::Point<double, 3> x;
    image->TransformContinuousIndexToPhysicalPoint(index, x);
    for (unsigned int a = 0; a < 3; ++a)
    {
      b[a][0] = std::min(b[a][0], x[a]);
      b[a][1] = std::max(b[a][1], x[a]);
    }
  }
  return b;
}

RegisterReport
RunRegistration(const RegisterInputs & in, StageTimer & timer)
{
  // Images that do not overlap in physical space cannot be registered (wrong origin, wrong file).
  const auto movingBox = PhysicalBounds(in.movingLabels);
  const auto fixedBox = PhysicalBounds(in.fixedLabels);
  for (unsigned int a = 0; a < 3; ++a)
  {
    if (movingBox[a][1] <= fixedBox[a][0] || fixedBox[a][1] <= movingBox[a][0])
    {
      throw std::runtime_error("the moving and fixed label images do not overlap in physical space (axis " +
                               std::to_string(a) + ": moving " + std::to_string(movingBox[a][0]) + " .. " +
                               std::to_string(movingBox[a][1]) + " mm, fixed " + std::to_string(fixedBox[a][0]) +
                               " .. " + std::to_string(fixedBox[a][1]) + " mm)");
    }
  }
  using Optimizer = itk::FEMElasticityOptimizer;
  MakeDirectory(in.out);
  const bmr::Scene scene = ScaledMeshSizes(in.scene, in.meshScale);
  scene.Validate();
  PrintSceneWarnings(scene);
  RegisterReport report;
  report.warnings = scene.Warnings();
  double finest = std::numeric_limits<double>::infinity(), coarsest = 0.0;
  for (const itk::ImageBase<3> * image : { static_cast<const itk::ImageBase<3> *>(in.movingLabels),
                                           static_cast<const itk::ImageBase<3> *>(in.fixedLabels) })
  {
    for (unsigned int a = 0; a < 3; ++a)
    {
      finest = std::min(finest, image->GetSpacing()[a]);
      coarsest = std::max(coarsest, image->GetSpacing()[a]);
    }
  }
  const auto warn = [&report](const std::vector<std::string> & warnings) {
    for (const std::string & w : warnings)
    {
      report.warnings.push_back(w);
      std::cout << "warning: " << w << std::endl;
    }
  };
  warn(scene.EstimationWarnings(finest, coarsest));

  timer.Begin("distance maps (fixed labels)");
  const auto maps = itk::ComputeSceneDistanceMaps(in.fixedLabels.GetPointer(), scene);
  timer.End(std::to_string(maps.size()) + " organs");

  SimulationOutputs sim;
  sim.mesh = MeshLabels(in.movingLabels, scene, timer, "mesh (CGAL Mesh_3)");
  warn(bmr::MeshResolutionWarnings(scene, sim.mesh));
  bool hasUnknown = false;
  for (const auto & l : scene.labels)
  {
    hasUnknown |= l.role == bmr::LabelRole::UnknownMaterial;
  }
  auto optimizer = Optimizer::New();
  auto fine = itk::TetrahedralMeshObject::New();
  fine->Set(sim.mesh);
  optimizer->SetMesh(fine);
  // Coarse-to-fine only when there is a modulus to sweep: nothing is meshed twice otherwise.
  if (hasUnknown && in.coarseFactor > 1.0)
  {
    auto coarse = itk::TetrahedralMeshObject::New();
    coarse->Set(MeshLabels(in.movingLabels, ScaledMeshSizes(scene, in.coarseFactor), timer, "coarse mesh (sweep)"));
    optimizer->SetCoarseMesh(coarse);
  }
  optimizer->SetScene(scene);
  for (const auto & kv : maps)
  {
    optimizer->SetDistanceMap(kv.first, kv.second);
  }
  optimizer->SetNumberOfSweepSamples(in.sweepSamples);
  optimizer->SetWallControlSpacing(in.wallControlSpacing);
  optimizer->SetWallRegularization(in.wallRegularization);
  optimizer->SetWallMotionAlongNormals(in.wallMotion == "normal");
  optimizer->SetLimitElementInversion(in.elementInversion == "limit");
  optimizer->SetMaximumNumberOfOuterIterations(in.maximumOuterIterations);
  optimizer->SetOuterGradientTolerance(in.outerTolerance);
  optimizer->AddObserver(itk::IterationEvent(), ProgressPrinter::New());
  std::cout << "  estimation (sweep of E on the coarse mesh, then L-BFGS-B over log E on the fine mesh):" << std::endl;
  optimizer->Update();
  for (const auto & r : optimizer->GetOuterIterations())
  {
    std::cout << "    outer " << std::setw(3) << r.iteration << "  E";
    for (double E : r.youngsModuli)
    {
      std::cout << " " << std::fixed << std::setprecision(2) << E << " kPa";
    }
    std::cout << "  Phi* " << std::scientific << std::setprecision(6) << r.value << std::endl;
  }
  if (!optimizer->GetOuterStopCondition().empty())
  {
    std::cout << "    outer stop: " << optimizer->GetOuterStopCondition() << std::endl;
  }
  for (const auto & kv : optimizer->GetTimings())
  {
    timer.Add("estimation: " + kv.first, kv.second);
  }
  sim.mesh = optimizer->GetOutput()->Get();

  // Per-element moduli, stress and the Dirichlet flags of the estimated state, for mesh.vtu.
  auto materials = bmr::SceneMaterials(scene);
  for (const auto & l : scene.labels)
  {
    const auto it = optimizer->GetEstimatedYoungsModuli().find(l.name);
    if (it != optimizer->GetEstimatedYoungsModuli().end())
    {
      materials[l.value].youngsModulus = it->second;
    }
  }
  const bmr::LinearElasticModel model(sim.mesh, materials);
  sim.simulation.displacement = sim.mesh.displacement;
  sim.simulation.force = sim.mesh.force;
  sim.simulation.vonMises = model.ComputeVonMisesStress(sim.mesh.displacement);
  sim.simulation.youngsModulus = model.GetElementYoungsModuli();
  sim.simulation.poissonRatio = model.GetElementPoissonRatios();
  sim.simulation.dirichlet.assign(sim.mesh.GetNumberOfPoints(), 0);
  for (std::int32_t n : bmr::SceneBoundaryConditions(scene, sim.mesh).dirichletNodes)
  {
    sim.simulation.dirichlet[n] = 1;
  }

  ComputeFields(sim, in.fixedLabels, in.movingLabels, timer);
  const auto warpedLabels = WarpAndWrite(in.out, sim, in.movingLabels, in.movingCT, timer);

  timer.Begin("report (Dice, Jacobian)");
  report.youngsModulus = optimizer->GetEstimatedYoungsModuli();
  report.finalValue = optimizer->GetFinalValue();
  report.identifiable = optimizer->GetIdentifiable();
  report.identifiability = optimizer->GetIdentifiabilityMessage();
  report.modulusUncertainty = optimizer->GetModulusUncertainty();
  report.residualStandardDeviation = optimizer->GetResidualStandardDeviation();
  for (const auto & kv : report.modulusUncertainty)
  {
    if (!std::isfinite(kv.second))
    {
      const std::string message = "Phi* has no positive curvature in the modulus of \"" + kv.first +
                                  "\" at the estimate: the surfaces do not determine it";
      report.warnings.push_back(message);
      std::cout << "warning: " << message << std::endl;
    }
    else if (kv.second > kUncertaintyWarningLogSigma)
    {
      std::ostringstream os;
      os << "the surfaces determine the modulus of \"" << kv.first << "\" only to a factor exp(+-"
         << std::setprecision(3) << kv.second << ") (one standard deviation from the residual "
         << report.residualStandardDeviation << " mm and the curvature of Phi*): treat it as "
         << report.youngsModulus[kv.first] * std::exp(-kv.second) << " to "
         << report.youngsModulus[kv.first] * std::exp(kv.second) << " kPa";
      report.warnings.push_back(os.str());
      std::cout << "warning: " << os.str() << std::endl;
    }
  }
  report.tetrahedra = sim.mesh.GetNumberOfTetrahedra();
  report.pullBack = sim.pullBack;
  report.invertedElements = sim.invertedElements;
  for (const auto & l : scene.labels)
  {
    if (l.role == bmr::LabelRole::Outside)
    {
      continue;
    }
    const itk::LabelOverlap overlap = itk::ComputeLabelOverlap<LabelImageType>(warpedLabels, in.fixedLabels, l.value);
    if (overlap.inA + overlap.inB > 0)
    {
      report.dice[l.name] = overlap.dice;
    }
  }
  const auto jacobian = itk::ComputeJacobianDeterminantStatistics(sim.pullBack.GetPointer());
  report.jacobianMinimum = jacobian.minimum;
  report.jacobianNonPositiveFraction = jacobian.fractionNonPositive;
  timer.End();

  timer.Begin("write history and report");
  std::vector<std::string> unknownNames;
  for (const auto & l : scene.labels)
  {
    if (l.role == bmr::LabelRole::UnknownMaterial)
    {
      unknownNames.push_back(l.name);
    }
  }
  // Every fine-mesh inner solve (stages "fine" and "curvature"), then the accepted outer iterates (stage "outer").
  auto history = optimizer->GetHistory();
  history.insert(history.end(), optimizer->GetOuterIterations().begin(), optimizer->GetOuterIterations().end());
  bmr::WriteTextFileAtomically(in.out + "/history.csv", HistoryCsv(history, unknownNames));
  if (!optimizer->GetSweep().empty())
  {
    bmr::WriteTextFileAtomically(in.out + "/sweep.csv", HistoryCsv(optimizer->GetSweep(), unknownNames));
  }
  timer.End();

  std::ostringstream j;
  j << std::setprecision(8) << "{\n  \"units\": {\"length\": \"mm\", \"modulus\": \"kPa\", \"force\": \"mN\", "
    << "\"phi\": \"mm^2\", \"time\": \"s\"},\n  \"youngs_modulus_kPa\": {";
  bool first = true;
  for (const auto & kv : report.youngsModulus)
  {
    j << (first ? "" : ", ") << JsonString(kv.first) << ": " << kv.second;
    first = false;
  }
  const bmr::SceneLabel * gauge = scene.FindLabel(optimizer->GetGaugeLabel());
  j << "},\n  \"gauge\": {\"label\": " << JsonString(optimizer->GetGaugeLabel())
    << ", \"youngs_modulus_kPa\": " << (gauge ? gauge->youngsModulus : 0.0) << "},\n"
    << "  \"identifiable\": " << (report.identifiable ? "true" : "false")
    << ",\n  \"identifiability\": " << JsonString(report.identifiability) << ",\n  \"youngs_modulus_uncertainty\": {";
  first = true;
  for (const auto & kv : report.modulusUncertainty)
  {
    const double E = report.youngsModulus[kv.first];
    j << (first ? "" : ", ") << JsonString(kv.first) << ": {\"sigma_log_E\": " << JsonNumber(kv.second)
      << ", \"one_sigma_interval_kPa\": [" << JsonNumber(E * std::exp(-kv.second)) << ", "
      << JsonNumber(E * std::exp(kv.second)) << "]}";
    first = false;
  }
  j << "},\n  \"residual_standard_deviation_mm\": " << report.residualStandardDeviation
    << ",\n  \"final_phi_mm2\": " << report.finalValue << ",\n  \"surface_distance_mm\": {";
  first = true;
  for (const auto & s : optimizer->GetSurfaceDistances())
  {
    j << (first ? "" : ", ") << JsonString(s.name) << ": {\"rms\": " << s.rms << ", \"max\": " << s.maximum
      << ", \"mean_signed\": " << s.mean << "}";
    first = false;
  }
  j << "},\n  \"dice\": {";
  first = true;
  for (const auto & kv : report.dice)
  {
    j << (first ? "" : ", ") << JsonString(kv.first) << ": " << kv.second;
    first = false;
  }
  j << "},\n  \"jacobian_determinant\": {\"minimum\": " << report.jacobianMinimum
    << ", \"fraction_nonpositive\": " << report.jacobianNonPositiveFraction << "},\n"
    << "  \"inverted_elements\": " << report.invertedElements
    << ",\n  \"step_limit\": {\"element_inversion\": " << JsonString(in.elementInversion)
    << ", \"rejected_trial_points\": " << optimizer->GetNumberOfRejectedSteps() << "},\n  \"warnings\": [";
  for (std::size_t i = 0; i < report.warnings.size(); ++i)
  {
    j << (i ? ", " : "") << JsonString(report.warnings[i]);
  }
  j << "],\n"
    << "  \"mesh\": {\"tetrahedra\": " << sim.mesh.GetNumberOfTetrahedra()
    << ", \"nodes\": " << sim.mesh.GetNumberOfPoints()
    << "},\n  \"iterations\": {\"sweep\": " << optimizer->GetSweep().size()
    << ", \"fine\": " << optimizer->GetHistory().size() << "},\n  \"wall_time_s\": {";
  first = true;
  double total = 0.0;
  for (const auto & s : timer.stages)
  {
    j << (first ? "" : ", ") << JsonString(s.first) << ": " << s.second;
    total += s.second;
    first = false;
  }
  j << ", \"total\": " << total << "}\n}\n";
  bmr::WriteTextFileAtomically(in.out + "/report.json", j.str());
  return report;
}

void
ParseFemSettings(const Arguments & args, RegisterInputs & in)
{
  const double samples = args.Number("--sweep-samples", in.sweepSamples);
  if (!(samples >= 3 && samples <= 100 && samples == std::floor(samples)))
  {
    throw UsageError("--sweep-samples must be an integer in [3, 100]");
  }
  in.sweepSamples = static_cast<unsigned int>(samples);
  in.coarseFactor = args.Number("--coarse-factor", in.coarseFactor);
  if (!(in.coarseFactor > 0.0 && in.coarseFactor <= 10.0))
  {
    throw UsageError("--coarse-factor must lie in (0, 10] (1 or less: sweep on the fine mesh)");
  }
  in.wallControlSpacing = args.Number("--wall-spacing-mm", in.wallControlSpacing);
  in.wallRegularization = args.Number("--wall-regularization", in.wallRegularization);
  if (!(in.wallRegularization >= 0.0))
  {
    throw UsageError("--wall-regularization must be >= 0");
  }
  in.wallMotion = args.Get("--wall-motion", in.wallMotion);
  if (in.wallMotion != "normal" && in.wallMotion != "free")
  {
    throw UsageError("--wall-motion must be normal or free");
  }
  if (!(in.wallControlSpacing >= 0.0))
  {
    throw UsageError("--wall-spacing-mm must be >= 0 (0: every wall node free)");
  }
  in.elementInversion = args.Get("--element-inversion", in.elementInversion);
  if (in.elementInversion != "allow" && in.elementInversion != "limit")
  {
    throw UsageError("--element-inversion must be allow or limit");
  }
  if (in.elementInversion == "limit" && in.wallControlSpacing > 0.0)
  {
    throw UsageError("--element-inversion limit needs --wall-spacing-mm 0 (one parameter per wall node)");
  }
  in.meshScale = args.Number("--mesh-scale", in.meshScale);
  if (!(in.meshScale >= 0.25 && in.meshScale <= 4.0))
  {
    throw UsageError("--mesh-scale must lie in [0.25, 4] (mesh sizes relative to the scene's)");
  }
  const double outer = args.Number("--max-outer-iterations", in.maximumOuterIterations);
  if (!(outer >= 1 && outer <= 1000 && outer == std::floor(outer)))
  {
    throw UsageError("--max-outer-iterations must be an integer in [1, 1000]");
  }
  in.maximumOuterIterations = static_cast<unsigned int>(outer);
  in.outerTolerance = args.Number("--outer-tolerance", in.outerTolerance);
  if (!(in.outerTolerance > 0.0 && in.outerTolerance < 1.0))
  {
    throw UsageError("--outer-tolerance must lie in (0, 1) (relative to Phi*)");
  }
}

int
RegisterCommand(const Arguments & args)
{
  RegisterInputs    in;
  const std::string movingCT = args.Require("--moving-ct");
  const std::string movingLabels = args.Require("--moving-labels");
  const std::string fixedCT = args.Require("--fixed-ct");
  const std::string fixedLabels = args.Require("--fixed-labels");
  const std::string scenePath = args.Require("--scene");
  in.out = args.Require("--out");
  ParseFemSettings(args, in);
  args.CheckAllUsed();

  StageTimer timer;
  std::cout << "biomechreg register -> " << in.out << std::endl;
  timer.Begin("read inputs");
  in.scene = bmr::ReadScene(scenePath);
  in.movingCT = ReadImage<CTImageType>(movingCT, "moving CT");
  in.movingLabels = ReadImage<LabelImageType>(movingLabels, "moving label image");
  // The fixed CT is read to check it; the fixed label image defines the output grid.
  ReadImage<CTImageType>(fixedCT, "fixed CT");
  in.fixedLabels = ReadImage<LabelImageType>(fixedLabels, "fixed label image");
  timer.End();
  const RegisterReport report = RunRegistration(in, timer);
  std::cout << "\n  recovered Young's moduli:";
  for (const auto & kv : report.youngsModulus)
  {
    std::cout << "  " << kv.first << " " << std::fixed << std::setprecision(1) << kv.second << " kPa"
              << UncertaintyText(report, kv.first);
  }
  std::cout << (report.identifiable ? "" : "\n  warning: ") << (report.identifiable ? "" : report.identifiability)
            << std::endl;
  PrintTimings(timer);
  return EXIT_SUCCESS;
}

} // namespace bmrcli
