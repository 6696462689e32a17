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
// Shared pieces of the biomechreg command-line tool: stage timer, image I/O,
// argument parsing, the phantom scenes and the forward simulation pipeline.
#ifndef biomechregCommon_h
#define biomechregCommon_h

#include "bmrAtomicFile.h"
#include "bmrDisplacementFieldRasterizer.h"
#include "bmrPhantom.h"
#include "bmrSimulation.h"
#include "bmrVtuWriter.h"
#include "itkGDCMImageIO.h"
#include "itkGDCMSeriesFileNames.h"
#include "itkImageFileReader.h"
#include "itkImageFileWriter.h"
#include "itkImageRegionConstIteratorWithIndex.h"
#include "itkImageRegionIterator.h"
#include "itkDefaultConvertPixelTraits.h"
#include "itkImageSeriesReader.h"
#include "itkImageWarper.h"
#include "itkLabelImageToTetrahedralMeshFilter.h"
#include "itkPhysicsDeformationFieldSource.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <iostream>
#include <map>
#include <set>
#include <sstream>
#include <sys/stat.h>
#include <type_traits>


namespace bmrcli {
using CTImageType = itk::Image<float, 3>;
using LabelImageType = itk::Image<std::int32_t, 3>;
using FieldType = itk::Image<itk::Vector<double, 3>, 3>;
using Clock = std::chrono::steady_clock;

struct UsageError : std::runtime_error
{
  using std::runtime_error::runtime_error;
};

/** Wall time of the stages of a run, printed as the summary table. */
struct StageTimer
{
  std::vector<std::pair<std::string, double>> stages;
  Clock::time_point                           start;
  std::string                                 current;

  void
  Begin(const std::string & name)
  {
    current = name;
    std::cout << "  " << std::left << std::setw(34) << (name + " ...") << std::flush;
    start = Clock::now();
  }
  void
  End(const std::string & detail = std::string())
  {
    const double s = std::chrono::duration<double>(Clock::now() - start).count();
    stages.emplace_back(current, s);
    std::cout << std::fixed << std::setprecision(2) << std::setw(7) << s << " s" << (detail.empty() ? "" : "  ")
              << detail << std::endl;
  }
  void
  Add(const std::string & name, double seconds)
  {
    stages.emplace_back(name, seconds);
  }
};

// ---------------------------------------------------------------- image I/O

inline bool
IsDirectory(const std::string & path)
{
  struct stat st;
  return ::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

inline void
MakeDirectory(const std::string & path)
{
  // Like mkdir -p: every missing parent is created too.
  for (std::size_t pos = path.find('/', 1);; pos = path.find('/', pos + 1))
  {
    const std::string prefix = path.substr(0, pos);
    if (!prefix.empty() && !IsDirectory(prefix) && ::mkdir(prefix.c_str(), 0755) != 0 && !IsDirectory(prefix))
    {
      throw std::runtime_error("cannot create output directory \"" + path + "\"");
    }
    if (pos == std::string::npos)
    {
      break;
    }
  }
}

/** Captures what a library prints on std::cerr while it lives (restores it after). Some image IOs
 * (MetaIO) report a truncated file only there and return a half-read image without throwing. */
class CerrCapture
{
public:
  CerrCapture()
    : m_Old(std::cerr.rdbuf(m_Text.rdbuf()))
  {}
  ~CerrCapture() { std::cerr.rdbuf(m_Old); }
  std::string
  FirstLine() const
  {
    std::string t = m_Text.str();
    t.erase(0, std::min(t.size(), t.find_first_not_of(" \n\t")));
    return t.substr(0, t.find('\n'));
  }

private:
  std::ostringstream m_Text;
  std::streambuf *   m_Old;
};

/** Largest image the tool reads: 2^31 voxels (a declared size beyond is a corrupt or absurd header). */
constexpr double MaximumNumberOfVoxels = 2147483648.0;

/** Throws naming the first voxel that is NaN or infinite (floating-point pixels and vectors of them). */
template<typename TImage>
void
CheckFinite(const TImage * image, const std::string & what)
{
  using ValueType = typename itk::NumericTraits<typename TImage::PixelType>::ValueType;
  if (!std::is_floating_point<ValueType>::value)
  {
    return;
  }
  const unsigned int components = itk::NumericTraits<typename TImage::PixelType>::GetLength(image->GetPixel({}));
  for (itk::ImageRegionConstIteratorWithIndex<TImage> it(image, image->GetBufferedRegion()); !it.IsAtEnd(); ++it)
  {
    const auto & v = it.Get();
    for (unsigned int c = 0; c < components; ++c)
    {
      if (!std::isfinite(
            static_cast<double>(itk::DefaultConvertPixelTraits<typename TImage::PixelType>::GetNthComponent(c, v))))
      {
        std::ostringstream os;
        os << what << ": voxel " << it.GetIndex() << " is not finite (NaN or infinite)";
        throw std::runtime_error(os.str());
      }
    }
  }
}

/** Reads a 3-D image from any file ITK reads, or a DICOM series directory (GDCM). Refuses images that are
 * not 3-D, declare more than MaximumNumberOfVoxels, have a zero, negative or non-finite spacing, or hold a
 * non-finite voxel. */
template<typename TImage>
typename TImage::Pointer
ReadImage(const std::string & path, const std::string & what)
{
  typename TImage::Pointer image;
  CerrCapture              diagnostics;
  try
  {
    if (IsDirectory(path))
    {
      auto names = itk::GDCMSeriesFileNames::New();
      names->SetUseSeriesDetails(true);
      names->SetDirectory(path);
      const auto & series = names->GetSeriesUIDs();
      if (series.empty())
      {
        throw std::runtime_error(what + " \"" + path + "\" is a directory without a DICOM series");
      }
      auto reader = itk::ImageSeriesReader<TImage>::New();
      reader->SetImageIO(itk::GDCMImageIO::New());
      reader->SetFileNames(names->GetFileNames(series.front()));
      reader->Update();
      image = reader->GetOutput();
    }
    else
    {
      auto reader = itk::ImageFileReader<TImage>::New();
      reader->SetFileName(path);
      reader->UpdateOutputInformation();
      const unsigned int dim = reader->GetImageIO()->GetNumberOfDimensions();
      if (dim != 3)
      {
        throw std::runtime_error(what + " \"" + path + "\" is " + std::to_string(dim) + "-D; a 3-D image is required");
      }
      double voxels = 1.0;
      for (unsigned int a = 0; a < dim; ++a)
      {
        voxels *= static_cast<double>(reader->GetImageIO()->GetDimensions(a));
      }
      if (voxels > MaximumNumberOfVoxels)
      {
        std::ostringstream os;
        os << what << " \"" << path << "\" declares " << voxels << " voxels (more than 2^31)";
        throw std::runtime_error(os.str());
      }
      reader->Update();
      image = reader->GetOutput();
    }
  }
  catch (const itk::ExceptionObject & e)
  {
    std::string description = e.GetDescription();
    const auto  nl = description.find('\n');
    throw std::runtime_error("cannot read " + what + " \"" + path + "\": " + description.substr(0, nl));
  }
  if (!diagnostics.FirstLine().empty())
  {
    throw std::runtime_error("cannot read " + what + " \"" + path + "\": " + diagnostics.FirstLine());
  }
  itk::GridGeometryOf(image).Validate((what + " \"" + path + "\"").c_str());
  CheckFinite(image.GetPointer(), what + " \"" + path + "\"");
  return image;
}

template<typename TImage>
void
WriteImage(const TImage * image, const std::string & path)
{
  const std::string tmp = bmr::TemporaryPathFor(path);
  auto              writer = itk::ImageFileWriter<TImage>::New();
  writer->SetInput(image);
  writer->SetFileName(tmp);
  writer->UseCompressionOn();
  try
  {
    writer->Update();
  }
  catch (const itk::ExceptionObject & e)
  {
    std::remove(tmp.c_str());
    throw std::runtime_error("cannot write \"" + path + "\": " + e.GetDescription());
  }
  bmr::CommitTemporaryFile(tmp, path);
}

// ------------------------------------------------------------ argument parsing

class Arguments
{
public:
  Arguments(int argc, char * argv[], int first)
  {
    for (int i = first; i < argc; ++i)
    {
      std::string key = argv[i];
      if (key.rfind("--", 0) != 0)
      {
        throw UsageError("unexpected argument \"" + key + "\"");
      }
      if (i + 1 >= argc)
      {
        throw UsageError("option " + key + " needs a value");
      }
      m_Values[key] = argv[++i];
    }
  }
  bool
  Has(const std::string & key) const
  {
    return m_Values.count(key) > 0;
  }
  std::string
  Get(const std::string & key, const std::string & fallback = std::string()) const
  {
    m_Used.insert(key);
    auto it = m_Values.find(key);
    return it == m_Values.end() ? fallback : it->second;
  }
  std::string
  Require(const std::string & key) const
  {
    if (!Has(key))
    {
      throw UsageError("missing required option " + key);
    }
    return Get(key);
  }
  double
  Number(const std::string & key, double fallback) const
  {
    if (!Has(key))
    {
      m_Used.insert(key);
      return fallback;
    }
    const std::string text = Get(key);
    char *            end = nullptr;
    const double      v = std::strtod(text.c_str(), &end);
    if (end == text.c_str() || *end != '\0' || !std::isfinite(v))
    {
      throw UsageError("option " + key + " expects a number, got \"" + text + "\"");
    }
    return v;
  }
  std::array<double, 3>
  Triple(const std::string & key, const std::array<double, 3> & fallback) const
  {
    if (!Has(key))
    {
      m_Used.insert(key);
      return fallback;
    }
    std::array<double, 3> v;
    const std::string     text = Get(key);
    std::istringstream    in(text);
    char                  comma1 = 0, comma2 = 0;
    if (!(in >> v[0] >> comma1 >> v[1] >> comma2 >> v[2]) || comma1 != ',' || comma2 != ',' || !in.eof())
    {
      throw UsageError("option " + key + " expects three comma-separated numbers, got \"" + text + "\"");
    }
    return v;
  }
  void
  CheckAllUsed() const
  {
    for (const auto & kv : m_Values)
    {
      if (m_Used.count(kv.first) == 0)
      {
        throw UsageError("unknown option " + kv.first);
      }
    }
  }

private:
  std::map<std::string, std::string> m_Values;
  mutable std::set<std::string>      m_Used;
};

// ------------------------------------------------------------------ scenes

/** The scene the estimator sees for the pelvis phantom: prostate modulus unknown. */
inline bmr::Scene
PelvisScene(double prostateE, bool unknown, double prostateNu = 0.40)
{
  bmr::Scene s;
  s.name = "pelvis phantom";
  using R = bmr::LabelRole;
  bmr::SceneLabel air{ "air", bmr::PelvisAir, R::Outside };
  bmr::SceneLabel tissue{ "soft_tissue", bmr::PelvisSoftTissue, R::Material, 10.0, 0.35 };
  bmr::SceneLabel prostate{
    "prostate", bmr::PelvisProstate, unknown ? R::UnknownMaterial : R::Material, prostateE, prostateNu
  };
  if (unknown)
  {
    // Wide enough for the dissertation's range (50-350 kPa) with room on both sides.
    prostate.lowerBound = 20.0;
    prostate.upperBound = 600.0;
  }
  s.labels = { air,
               tissue,
               prostate,
               { "bladder", bmr::PelvisBladder, R::Hollow },
               { "rectum", bmr::PelvisRectum, R::Hollow },
               { "bone", bmr::PelvisBone, R::Fixed } };
  s.gauge = "soft_tissue";
  s.forceSurfaces = { "bladder", "rectum" };
  s.objective = { { "prostate", 1.0 }, { "bladder", 1.0 }, { "rectum", 1.0 } };
  s.roiMargin = 25.0;
  s.mesh.cellSize = 7.0;
  s.mesh.facetSize = 6.0;
  s.mesh.facetDistance = 0.5;
  s.mesh.cellSizePerLabel[bmr::PelvisProstate] = 4.5;
  return s;
}

inline bmr::Scene
SpheresScene(double innerE, bool unknown)
{
  bmr::Scene s;
  s.name = "concentric spheres";
  using R = bmr::LabelRole;
  bmr::SceneLabel inner{ "inner", bmr::SphereInnerCore, unknown ? R::UnknownMaterial : R::Material, innerE, 0.40 };
  if (unknown)
  {
    inner.lowerBound = 30.0;
    inner.upperBound = 300.0;
  }
  s.labels = { { "outside", bmr::SphereOutside, R::Outside },
               { "outer", bmr::SphereOuterShell, R::Material, 10.0, 0.35 },
               inner };
  s.gauge = "outer";
  s.forceSurfaces = { "outside" };
  s.objective = { { "inner", 1.0 }, { "outer", 1.0 } };
  s.mesh.cellSize = 4.0;
  s.mesh.facetSize = 3.0;
  s.mesh.facetDistance = 0.5;
  return s;
}

// -------------------------------------------------------------- simulation

struct SimulationOutputs
{
  bmr::TetrahedralMesh   mesh;
  bmr::ForwardSimulation simulation;
  FieldType::Pointer     pullBack;
  FieldType::Pointer     push;
  std::size_t            invertedElements{ 0 }; ///< elements the displacement inverts (no pull-back there)
};

/** Meshes the moving labels for \a scene (CGAL Mesh_3), timing it. */
inline bmr::TetrahedralMesh
MeshLabels(const LabelImageType * movingLabels, const bmr::Scene & scene, StageTimer & timer, const std::string & stage)
{
  timer.Begin(stage);
  auto mesher = itk::LabelImageToTetrahedralMeshFilter<LabelImageType>::New();
  mesher->SetInput(movingLabels);
  mesher->SetScene(scene);
  mesher->Update();
  bmr::TetrahedralMesh   mesh = mesher->GetOutput()->Get();
  const bmr::MeshQuality q = mesher->GetMeshQuality();
  std::ostringstream     detail;
  detail << mesh.GetNumberOfTetrahedra() << " tetrahedra, " << mesh.GetNumberOfPoints() << " nodes, min dihedral "
         << std::setprecision(1) << q.minimumDihedralAngleDegrees << " deg";
  timer.End(detail.str());
  return mesh;
}

/** The pull-back field on the fixed grid and the push field on the moving grid of out.mesh's displacement. */
inline void
ComputeFields(SimulationOutputs &       out,
              const itk::ImageBase<3> * fixedReference,
              const itk::ImageBase<3> * movingReference,
              StageTimer &              timer)
{
  auto meshObject = itk::TetrahedralMeshObject::New();
  meshObject->Set(out.mesh);
  timer.Begin("pull-back field (fixed -> moving)");
  auto pull = itk::PhysicsDeformationFieldSource<FieldType>::New();
  pull->SetMesh(meshObject);
  pull->SetReferenceImage(fixedReference);
  pull->Update();
  out.pullBack = pull->GetOutput();
  out.invertedElements = pull->GetNumberOfInvertedElements();
  timer.End();
  timer.Begin("push field (moving -> fixed)");
  auto push = itk::PhysicsDeformationFieldSource<FieldType>::New();
  push->SetMesh(meshObject);
  push->SetReferenceImage(movingReference);
  push->SetFieldDirection(itk::PhysicsDeformationFieldSource<FieldType>::FieldDirectionEnum::MovingToFixed);
  push->Update();
  out.push = push->GetOutput();
  timer.End();
}

/** Prints the scene's warnings (bmr::Scene::Warnings) on stdout, one line each. */
inline void
PrintSceneWarnings(const bmr::Scene & scene)
{
  for (const std::string & w : scene.Warnings())
  {
    std::cout << "warning: " << w << std::endl;
  }
}

/** Mesh -> FEM -> fields, timing each stage. */
inline SimulationOutputs
RunSimulation(const LabelImageType *    movingLabels,
              const bmr::Scene &        scene,
              const itk::ImageBase<3> * fixedReference,
              StageTimer &              timer)
{
  PrintSceneWarnings(scene);
  SimulationOutputs out;
  out.mesh = MeshLabels(movingLabels, scene, timer, "mesh (CGAL Mesh_3)");
  for (const std::string & w : bmr::MeshResolutionWarnings(scene, out.mesh))
  {
    std::cout << "warning: " << w << std::endl;
  }

  timer.Begin("FEM (assemble, factorise, solve)");
  out.simulation = bmr::SimulateScene(scene, out.mesh);
  out.mesh.displacement = out.simulation.displacement;
  out.mesh.force = out.simulation.force;
  double umax = 0.0;
  for (std::size_t n = 0; n < out.mesh.GetNumberOfPoints(); ++n)
  {
    umax = std::max(
      umax,
      std::hypot(out.mesh.displacement[3 * n], out.mesh.displacement[3 * n + 1], out.mesh.displacement[3 * n + 2]));
  }
  std::ostringstream fem;
  fem << "max |u| " << std::setprecision(2) << umax << " mm";
  timer.End(fem.str());
  const bmr::SolverTimings & t = out.simulation.timings;
  timer.stages.pop_back();
  timer.Add("assemble", t.assemble);
  timer.Add("factorise", t.analyse + t.factorise);
  timer.Add("solve", t.solve);
  ComputeFields(out, fixedReference, movingLabels, timer);
  return out;
}

inline void
WriteMesh(const std::string & path, const SimulationOutputs & s)
{
  std::vector<double> dirichlet(s.simulation.dirichlet.begin(), s.simulation.dirichlet.end());
  std::vector<double> labels(s.mesh.labels.begin(), s.mesh.labels.end());
  bmr::WriteVtu(
    path,
    s.mesh,
    { { "displacement", 3, s.mesh.displacement }, { "force", 3, s.mesh.force }, { "dirichlet", 1, dirichlet } },
    { { "label", 1, labels },
      { "youngs_modulus", 1, s.simulation.youngsModulus },
      { "poisson_ratio", 1, s.simulation.poissonRatio },
      { "von_mises", 1, s.simulation.vonMises } });
}

template<typename TImage>
typename TImage::Pointer
Warp(const TImage * image, const FieldType * field, bool labels, typename TImage::PixelType outside)
{
  auto warper = itk::ImageWarper<TImage, FieldType>::New();
  warper->SetInput(image);
  warper->SetDisplacementField(field);
  warper->SetInterpolation(labels ? itk::ImageWarper<TImage, FieldType>::InterpolationEnum::NearestNeighbor
                                  : itk::ImageWarper<TImage, FieldType>::InterpolationEnum::Linear);
  warper->SetDefaultPixelValue(outside);
  warper->Update();
  return warper->GetOutput();
}

inline void
PrintTimings(const StageTimer & timer)
{
  std::cout << "\n  stage                               wall [s]\n";
  double total = 0.0;
  for (const auto & s : timer.stages)
  {
    std::cout << "  " << std::left << std::setw(36) << s.first << std::right << std::fixed << std::setprecision(3)
              << std::setw(8) << s.second << "\n";
    total += s.second;
  }
  std::cout << "  " << std::left << std::setw(36) << "total" << std::right << std::setw(8) << total << std::endl;
}

/** Warps the moving labels (nearest neighbour) and CT (linear, if given) through the pull-back
 * field and writes mesh.vtu, field.nrrd, forward_field.nrrd and the warped images into \a out.
 * Returns the warped labels. */
inline LabelImageType::Pointer
WarpAndWrite(const std::string &       out,
             const SimulationOutputs & sim,
             const LabelImageType *    labels,
             const CTImageType *       ct,
             StageTimer &              timer)
{
  timer.Begin("warp (CT linear; labels nearest)");
  auto                 warpedLabels = Warp<LabelImageType>(labels, sim.pullBack, true, 0);
  CTImageType::Pointer warpedCT;
  if (ct)
  {
    warpedCT = Warp<CTImageType>(ct, sim.pullBack, false, -1000.0f);
  }
  timer.End();
  timer.Begin("write outputs");
  WriteMesh(out + "/mesh.vtu", sim);
  WriteImage<FieldType>(sim.pullBack, out + "/field.nrrd");
  WriteImage<FieldType>(sim.push, out + "/forward_field.nrrd");
  WriteImage<LabelImageType>(warpedLabels, out + "/warped_labels.nrrd");
  if (ct)
  {
    WriteImage<CTImageType>(warpedCT, out + "/warped_ct.nrrd");
  }
  timer.End();
  return warpedLabels;
}

// ---------------------------------------------------------------- register

/** Inputs of a registration run (biomechreg register, the demo). */
struct RegisterInputs
{
  LabelImageType::Pointer movingLabels;
  LabelImageType::Pointer fixedLabels;
  CTImageType::Pointer    movingCT;
  bmr::Scene              scene;
  std::string             out;
  unsigned int            sweepSamples{ 10 };
  double                  coarseFactor{ 1.6 };        ///< coarse mesh sizes = scene sizes x this (<= 1: no coarse mesh)
  double                  wallControlSpacing{ 0.0 };  ///< mm, FEMElasticityOptimizer::SetWallControlSpacing
  double                  wallRegularization{ 0.01 }; ///< FEMElasticityOptimizer::SetWallRegularization
  std::string             wallMotion{ "normal" }; ///< "normal": walls move along their normals; "free": any direction
  std::string  elementInversion{ "allow" };       ///< "limit": FEMElasticityOptimizer::SetLimitElementInversion(true)
  double       meshScale{ 1.0 };                  ///< mesh sizes = scene sizes x this (> 1: coarser, faster)
  unsigned int maximumOuterIterations{ 20 };      ///< FEMElasticityOptimizer::SetMaximumNumberOfOuterIterations
  double       outerTolerance{ 1e-4 };            ///< FEMElasticityOptimizer::SetOuterGradientTolerance
};

/** What a registration run measured, as written to report.json. */
struct RegisterReport
{
  std::map<std::string, double> youngsModulus; ///< kPa, unknown labels
  std::map<std::string, double> dice;
  double                        jacobianMinimum{ 0.0 };
  double                        jacobianNonPositiveFraction{ 0.0 };
  std::size_t                   invertedElements{ 0 }; ///< mesh elements inverted by the estimated deformation
  std::vector<std::string>      warnings;
  double                        finalValue{ 0.0 };
  bool                          identifiable{ true };
  std::string                   identifiability;
  std::map<std::string, double> modulusUncertainty;               ///< standard deviation of log E by unknown label
  double                        residualStandardDeviation{ 0.0 }; ///< mm, objective nodes at the estimate
  std::size_t                   tetrahedra{ 0 };
  FieldType::Pointer            pullBack; ///< fixed -> moving field [mm], as written to field.nrrd
};

/** " (x/ exp(sigma) = +-N %, one standard deviation)" for an unknown label whose uncertainty was computed. */
inline std::string
UncertaintyText(const RegisterReport & report, const std::string & label)
{
  const auto it = report.modulusUncertainty.find(label);
  if (it == report.modulusUncertainty.end())
  {
    return std::string();
  }
  if (!std::isfinite(it->second))
  {
    return " (uncertainty: not determined, Phi* has no positive curvature there)";
  }
  std::ostringstream os;
  os << " (uncertainty x/ exp(" << std::setprecision(3) << it->second << "), i.e. +-" << std::setprecision(2)
     << 100.0 * it->second << " %, one standard deviation)";
  return os.str();
}

/** \a scene with every mesh size (cell, facet, facet distance, per-label cell sizes) multiplied by \a factor. */
inline bmr::Scene
ScaledMeshSizes(bmr::Scene scene, double factor)
{
  scene.mesh.cellSize *= factor;
  scene.mesh.facetSize *= factor;
  scene.mesh.facetDistance *= factor;
  for (auto & kv : scene.mesh.cellSizePerLabel)
  {
    kv.second *= factor;
  }
  return scene;
}

/** Distance maps -> meshes -> FEMElasticityOptimizer -> fields -> warped images -> files in inputs.out. */
RegisterReport
RunRegistration(const RegisterInputs & inputs, StageTimer & timer);

int
RegisterCommand(const Arguments & args);

/** Reads the FEM settings --sweep-samples, --coarse-factor, --wall-spacing-mm, --wall-regularization,
 * --mesh-scale, --max-outer-iterations and --outer-tolerance into \a in (register, compare). */
void
ParseFemSettings(const Arguments & args, RegisterInputs & in);

// ---------------------------------------------------------------- phantom

/** Options of one phantom pair (biomechreg phantom, phantom-set, the demo). */
struct PhantomOptions
{
  std::string       scene{ "pelvis" };
  std::string       out;
  bmr::GridGeometry grid;
  double            prostateE{ 50.0 };
  double            prostateNu{ 0.40 }; ///< true Poisson's ratio of the prostate (the estimation scene assumes 0.40)
  double            bladderMM{ 4.0 };
  double            rectumMM{ 3.0 };
  std::string       wallLoad{ "normal" };  ///< "normal": walls move along their normals; "point": radial from a point
  double            tumourFraction{ 0.0 }; ///< volume fraction of the prostate taken by a stiffer tumour (truth only)
  double            tumourE{ 100.0 };      ///< kPa
  double            bladderKPa{ 0.0 };     ///< > 0: the bladder and rectum are loaded by pressure [kPa] instead
  double            rectumKPa{ 0.0 };
  double            noiseHU{ 10.0 };
  std::uint64_t     seed{ 1 };
  unsigned int      numberOfSeeds{ 3 }; ///< implanted seeds in the prostate (pelvis)
  double            truthRefinement{ 0.75 };
};

/** Makes a moving/fixed pair in o.out: the fixed images are the moving ones warped by a forward
 * simulation with known moduli on a finer, independently meshed model (biomechreg.cxx). */
void
MakePhantom(const PhantomOptions & o, StageTimer & timer);

// ---------------------------------------------------------------- Demons and compare

/** Settings of the Demons baseline (itk::DemonsBaselineRegistrationFilter; defaults as documented there). */
struct DemonsSettings
{
  std::string  variant{ "diffeomorphic" }; ///< or "symmetric" (fast symmetric forces)
  unsigned int levels{ 3 };
  unsigned int iterations{ 50 }; ///< per level
  double       sigma{ 1.5 };     ///< field smoothing [voxels]
  bool         histogramMatching{ true };
};

/** Reads --demons-variant, --demons-levels, --demons-iterations, --demons-sigma, --histogram-matching. */
DemonsSettings
ParseDemonsSettings(const Arguments & args);

/** Demons of the moving CT onto the fixed CT; returns the fixed -> moving field [mm]. The labels are
 * used only when \a flatten names organs to flatten. */
FieldType::Pointer
RunDemons(const CTImageType *               fixedCT,
          const CTImageType *               movingCT,
          const LabelImageType *            fixedLabels,
          const LabelImageType *            movingLabels,
          const std::vector<std::int32_t> & flatten,
          const DemonsSettings &            settings);

/** Comma-separated labels, by value or (with a scene) by name; "none" gives an empty list. */
std::vector<std::int32_t>
ParseLabelList(const std::string & text, const bmr::Scene * scene);

int
DemonsCommand(const Arguments & args);
int
CompareCommand(const Arguments & args);
int
PhantomSetCommand(const Arguments & args);

} // namespace bmrcli

#endif
