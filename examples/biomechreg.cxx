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
//   biomechreg                      demo: pelvis phantom -> forward simulation -> fields -> warped images
//   biomechreg phantom ...          synthetic moving/fixed pair with ground truth
//   biomechreg simulate ...         forward simulation of a scene on a moving label map
// Every error is one line on stderr and a non-zero exit; outputs are written to
// temporary names and renamed when complete.
#include "bmrAtomicFile.h"
#include "bmrDisplacementFieldRasterizer.h"
#include "bmrPhantom.h"
#include "bmrSimulation.h"
#include "bmrVtuWriter.h"
#include "itkGDCMImageIO.h"
#include "itkGDCMSeriesFileNames.h"
#include "itkImageFileReader.h"
#include "itkImageFileWriter.h"
#include "itkImageRegionIterator.h"
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

namespace {
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

bool
IsDirectory(const std::string & path)
{
  struct stat st;
  return ::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

void
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

/** Reads a 3-D image from any file ITK reads, or a DICOM series directory (GDCM). */
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
bmr::Scene
PelvisScene(double prostateE, bool unknown)
{
  bmr::Scene s;
  s.name = "pelvis phantom";
  using R = bmr::LabelRole;
  bmr::SceneLabel air{ "air", bmr::PelvisAir, R::Outside };
  bmr::SceneLabel tissue{ "soft_tissue", bmr::PelvisSoftTissue, R::Material, 10.0, 0.35 };
  bmr::SceneLabel prostate{
    "prostate", bmr::PelvisProstate, unknown ? R::UnknownMaterial : R::Material, prostateE, 0.40
  };
  if (unknown)
  {
    prostate.lowerBound = 30.0;
    prostate.upperBound = 300.0;
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
  s.mesh.facetDistance = 1.5;
  s.mesh.cellSizePerLabel[bmr::PelvisProstate] = 4.5;
  return s;
}

bmr::Scene
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
};

/** Mesh -> FEM -> fields, timing each stage. */
SimulationOutputs
RunSimulation(const LabelImageType *    movingLabels,
              const bmr::Scene &        scene,
              const itk::ImageBase<3> * fixedReference,
              StageTimer &              timer)
{
  SimulationOutputs out;
  timer.Begin("mesh (CGAL Mesh_3)");
  auto mesher = itk::LabelImageToTetrahedralMeshFilter<LabelImageType>::New();
  mesher->SetInput(movingLabels);
  mesher->SetScene(scene);
  mesher->Update();
  out.mesh = mesher->GetOutput()->Get();
  const bmr::MeshQuality q = mesher->GetMeshQuality();
  std::ostringstream     detail;
  detail << out.mesh.GetNumberOfTetrahedra() << " tetrahedra, " << out.mesh.GetNumberOfPoints()
         << " nodes, min dihedral " << std::setprecision(1) << q.minimumDihedralAngleDegrees << " deg";
  timer.End(detail.str());

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

  auto meshObject = itk::TetrahedralMeshObject::New();
  meshObject->Set(out.mesh);
  timer.Begin("pull-back field (fixed -> moving)");
  auto pull = itk::PhysicsDeformationFieldSource<FieldType>::New();
  pull->SetMesh(meshObject);
  pull->SetReferenceImage(fixedReference);
  pull->Update();
  out.pullBack = pull->GetOutput();
  timer.End();
  timer.Begin("push field (moving -> fixed)");
  auto push = itk::PhysicsDeformationFieldSource<FieldType>::New();
  push->SetMesh(meshObject);
  push->SetReferenceImage(movingLabels);
  push->SetFieldDirection(itk::PhysicsDeformationFieldSource<FieldType>::FieldDirectionEnum::MovingToFixed);
  push->Update();
  out.push = push->GetOutput();
  timer.End();
  return out;
}

void
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

void
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
LabelImageType::Pointer
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

// ----------------------------------------------------------------- phantom

struct PhantomOptions
{
  std::string       scene{ "pelvis" };
  std::string       out;
  bmr::GridGeometry grid;
  double            prostateE{ 50.0 };
  double            bladderMM{ 4.0 };
  double            rectumMM{ 3.0 };
  double            noiseHU{ 10.0 };
  std::uint64_t     seed{ 1 };
  double            truthRefinement{ 0.75 };
};

std::string
Json3(const std::array<double, 3> & p)
{
  std::ostringstream o;
  o << std::setprecision(10) << "[" << p[0] << ", " << p[1] << ", " << p[2] << "]";
  return o.str();
}

/** Makes a moving/fixed pair: the fixed images are the moving ones warped by a
 * forward simulation with known moduli on a finer, independently meshed model. */
void
MakePhantom(const PhantomOptions & o, StageTimer & timer)
{
  MakeDirectory(o.out);
  const bool         pelvis = o.scene == "pelvis";
  bmr::PhantomVolume moving;
  timer.Begin("phantom volume");
  std::array<double, 3> centre;
  if (pelvis)
  {
    bmr::PelvisPhantomParameters p;
    p.grid = o.grid;
    p.seedPlacementSeed = o.seed;
    p.noiseSigmaHU = o.noiseHU;
    p.noiseSeed = 1000 + o.seed;
    moving = bmr::MakePelvisPhantom(p);
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
  bmr::Scene truth = pelvis ? PelvisScene(o.prostateE, false) : SpheresScene(o.prostateE, false);
  truth.mesh.cellSize *= o.truthRefinement;
  truth.mesh.facetSize *= o.truthRefinement;
  truth.mesh.facetDistance *= o.truthRefinement;
  for (auto & kv : truth.mesh.cellSizePerLabel)
  {
    kv.second *= o.truthRefinement;
  }
  truth.mesh.randomSeed = 12345;
  if (pelvis)
  {
    truth.loads = {
      { "bladder",
        bmr::SceneLoad::Type::RadialDisplacement,
        { { centre[0], centre[1] - 5, centre[2] + 30 } },
        o.bladderMM },
      { "rectum", bmr::SceneLoad::Type::RadialDisplacement, { { centre[0], centre[1] + 38, centre[2] } }, o.rectumMM }
    };
  }
  else
  {
    truth.loads = { { "outside", bmr::SceneLoad::Type::RadialDisplacement, centre, -o.bladderMM } };
  }
  truth.Validate();

  auto              movingCT = itk::MakeImageOnGrid<CTImageType>(moving.grid, moving.ct);
  auto              movingLabels = itk::MakeImageOnGrid<LabelImageType>(moving.grid, moving.labels);
  SimulationOutputs sim = RunSimulation(movingLabels, truth, movingLabels, timer);

  timer.Begin("warp to the fixed volume");
  auto fixedCT = Warp<CTImageType>(movingCT, sim.pullBack, false, -1000.0f);
  auto fixedLabels = Warp<LabelImageType>(movingLabels, sim.pullBack, true, 0);
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
  t << "},\n  \"wall_displacements\": [";
  for (std::size_t i = 0; i < truth.loads.size(); ++i)
  {
    t << (i ? ", " : "") << "{\"surface\": \"" << truth.loads[i].surface
      << "\", \"type\": \"radial_displacement\", \"center_mm\": " << Json3(truth.loads[i].center)
      << ", \"magnitude_mm\": " << truth.loads[i].magnitude << "}";
  }
  t << "],\n  \"truth_mesh\": {\"tetrahedra\": " << sim.mesh.GetNumberOfTetrahedra()
    << ", \"nodes\": " << sim.mesh.GetNumberOfPoints() << ", \"cell_size_mm\": " << truth.mesh.cellSize
    << "},\n  \"ct_noise_sigma_HU\": " << o.noiseHU << ",\n  \"landmarks\": [\n"
    << landmarksJson.str() << "\n  ]\n}\n";
  bmr::WriteTextFileAtomically(o.out + "/truth.json", t.str());
  timer.End();
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
  o.bladderMM = args.Number("--bladder-mm", o.scene == "pelvis" ? 4.0 : 1.5);
  o.rectumMM = args.Number("--rectum-mm", 3.0);
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
  std::cout << "biomechreg demo: pelvis phantom -> forward simulation -> displacement fields -> warped images\n"
            << "(outputs in ./" << dir << "; run 'biomechreg help' for the subcommands)\n\n";
  StageTimer     timer;
  PhantomOptions o;
  o.out = dir;
  o.grid = bmr::PelvisPhantomParameters().grid;
  std::cout << "1. phantom pair with known truth (prostate 50 kPa, tissue 10 kPa, bladder +4 mm, rectum +3 mm)\n";
  MakePhantom(o, timer);

  std::cout << "\n2. forward simulation of the truth scene on the estimation mesh\n";
  bmr::Scene scene = bmr::ReadScene(dir + "/truth_scene.json");
  bmr::Scene coarse = PelvisScene(50.0, false);
  scene.mesh = coarse.mesh; // the estimation mesh sizes, not the truth mesh's
  auto              labels = ReadImage<LabelImageType>(dir + "/moving_labels.nrrd", "moving label image");
  auto              ct = ReadImage<CTImageType>(dir + "/moving_ct.nrrd", "moving CT");
  auto              fixedLabels = ReadImage<LabelImageType>(dir + "/fixed_labels.nrrd", "fixed label image");
  StageTimer        run;
  const std::string out = dir + "/simulate";
  MakeDirectory(out);
  SimulationOutputs sim = RunSimulation(labels, scene, labels, run);
  auto              warpedLabels = WarpAndWrite(out, sim, labels, ct, run);

  // Agreement of the simulated warp with the truth-mesh warp: Dice per organ.
  std::cout << "\n  Dice of warped moving labels vs fixed labels (coarse estimation mesh vs finer truth mesh):\n";
  const auto *      a = warpedLabels->GetBufferPointer();
  const auto *      b = fixedLabels->GetBufferPointer();
  const std::size_t n = fixedLabels->GetBufferedRegion().GetNumberOfPixels();
  for (std::int32_t l : { 2, 3, 4 })
  {
    std::size_t na = 0, nb = 0, both = 0;
    for (std::size_t i = 0; i < n; ++i)
    {
      na += a[i] == l;
      nb += b[i] == l;
      both += a[i] == l && b[i] == l;
    }
    std::cout << "    " << std::left << std::setw(10)
              << (l == 2   ? "prostate"
                  : l == 3 ? "bladder"
                           : "rectum")
              << std::fixed << std::setprecision(4) << 2.0 * both / std::max<std::size_t>(1, na + nb) << "\n";
  }
  std::cout << "\nPhantom generation:";
  PrintTimings(timer);
  std::cout << "\nSimulation on the estimation mesh:";
  PrintTimings(run);
  std::cout << "\nWrote " << dir << "/{moving,fixed}_{ct,labels}.nrrd, scene.json, truth.json, landmarks_*.csv, and "
            << out << "/{mesh.vtu, field.nrrd, forward_field.nrrd, warped_ct.nrrd, warped_labels.nrrd}" << std::endl;
  return EXIT_SUCCESS;
}

void
PrintUsage(std::ostream & os)
{
  os << "usage:\n"
        "  biomechreg                      run the demo into ./biomechreg-demo\n"
        "  biomechreg phantom --out DIR [--scene pelvis|spheres] [--size NX,NY,NZ] [--spacing SX,SY,SZ mm]\n"
        "                     [--origin X,Y,Z mm] [--rotate-z-deg A] [--true-E-kPa E] [--bladder-mm D]\n"
        "                     [--rectum-mm D] [--noise-HU S] [--seed N]\n"
        "  biomechreg simulate --moving-labels FILE --scene FILE --out DIR [--moving-ct FILE] [--reference IMAGE]\n"
        "Images: NRRD, NIfTI, MetaImage, ... or a DICOM series directory. Units: mm (LPS), kPa, mN.\n";
}
} // namespace

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
