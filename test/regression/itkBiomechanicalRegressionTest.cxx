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
// Regression of the whole forward pipeline (phantom -> mesh -> FEM -> fields -> warp)
// against baseline images, run with a given number of threads.
// Usage: itkBiomechanicalRegressionTest BaselineDir OutputPrefix Threads
// With BMR_WRITE_BASELINES=1 in the environment the baselines are (re)written instead.
#include "bmrPhantom.h"
#include "bmrSimulation.h"
#include "bmrTestUtilities.h"
#include "itkGridGeometryConversion.h"
#include "itkImageFileReader.h"
#include "itkImageFileWriter.h"
#include "itkImageWarper.h"
#include "itkLabelImageToTetrahedralMeshFilter.h"
#include "itkPhysicsDeformationFieldSource.h"

#include <cmath>
#include <cstdlib>

namespace {
using bmr::test::Expect;
using bmr::test::ToString;
using CTType = itk::Image<float, 3>;
using LabelType = itk::Image<std::int32_t, 3>;
using FieldType = itk::Image<itk::Vector<double, 3>, 3>;

template<typename TImage>
void
Write(const TImage * image, const std::string & path)
{
  auto w = itk::ImageFileWriter<TImage>::New();
  w->SetInput(image);
  w->SetFileName(path);
  w->UseCompressionOn();
  w->Update();
}

/** Largest absolute difference per scalar component; -1 when the grids differ. */
template<typename TImage, typename TValue>
double
MaxDifference(const TImage *      a,
              const std::string & baselinePath,
              TValue (*component)(const typename TImage::PixelType &, unsigned int),
              unsigned int  components,
              std::size_t & differing,
              double        tolerance)
{
  auto reader = itk::ImageFileReader<TImage>::New();
  reader->SetFileName(baselinePath);
  reader->Update();
  const TImage * b = reader->GetOutput();
  if (a->GetLargestPossibleRegion() != b->GetLargestPossibleRegion() ||
      (a->GetOrigin() - b->GetOrigin()).GetNorm() > 1e-6)
  {
    return -1.0;
  }
  const std::size_t n = a->GetBufferedRegion().GetNumberOfPixels();
  double            worst = 0.0;
  differing = 0;
  for (std::size_t i = 0; i < n; ++i)
  {
    bool differs = false;
    for (unsigned int c = 0; c < components; ++c)
    {
      const double d = std::abs(static_cast<double>(component(a->GetBufferPointer()[i], c)) -
                                static_cast<double>(component(b->GetBufferPointer()[i], c)));
      worst = std::max(worst, d);
      differs = differs || d > tolerance;
    }
    differing += differs;
  }
  return worst;
}

/** The checks of one output against its baseline: the grids agree (MaxDifference() >= 0; \a differing is
 * only set then) and no voxel differs by more than the tolerance. */
bool
MatchesBaseline(const std::string & name, double maxDifference, std::size_t differing, const std::string & tolerance)
{
  if (!Expect(maxDifference >= 0.0, name + ": the grid (region and origin to 1e-6 mm) matches the baseline's"))
  {
    return false;
  }
  return Expect(differing == 0,
                name + ": no voxel differs from the baseline by more than " + tolerance + " (got " +
                  ToString(differing) + ", max difference " + ToString(maxDifference) + ")");
}

double
VectorComponent(const FieldType::PixelType & v, unsigned int c)
{
  return v[c];
}
float
Scalar(const float & v, unsigned int)
{
  return v;
}
std::int32_t
Label(const std::int32_t & v, unsigned int)
{
  return v;
}
} // namespace

int
itkBiomechanicalRegressionTest(int argc, char * argv[])
{
  if (argc < 4)
  {
    std::cerr << "usage: " << argv[0] << " BaselineDir OutputPrefix Threads" << std::endl;
    return EXIT_FAILURE;
  }
  const std::string baseline = argv[1];
  const std::string prefix = argv[2];
  const int         threads = std::atoi(argv[3]);
  itk::MultiThreaderBase::SetGlobalDefaultNumberOfThreads(threads);
  itk::MultiThreaderBase::SetGlobalMaximumNumberOfThreads(threads);

  // Concentric spheres, 40^3 voxels of 2 mm; the outer surface pressed in by 1.5 mm.
  bmr::SpherePhantomParameters p;
  p.grid.size = { { 40, 40, 40 } };
  p.grid.spacing = { { 2.0, 2.0, 2.0 } };
  p.grid.origin = { { -39.0, -39.0, -39.0 } };
  const bmr::PhantomVolume phantom = bmr::MakeSpherePhantom(p);
  auto                     ct = itk::MakeImageOnGrid<CTType>(phantom.grid, phantom.ct);
  auto                     labels = itk::MakeImageOnGrid<LabelType>(phantom.grid, phantom.labels);

  const bmr::Scene scene = bmr::ParseScene(R"({
    "labels": [{"name": "outside", "value": 0, "role": "outside"},
               {"name": "outer", "value": 1, "role": "material", "youngs_modulus_kPa": 10, "poisson_ratio": 0.35},
               {"name": "inner", "value": 2, "role": "material", "youngs_modulus_kPa": 50, "poisson_ratio": 0.4}],
    "loads": [{"surface": "outside", "type": "radial_displacement", "center_mm": [0, 0, 0], "magnitude_mm": -1.5}],
    "mesh": {"cell_size_mm": 5, "facet_size_mm": 4, "facet_distance_mm": 0.8}})",
                                           "regression scene");
  auto             mesher = itk::LabelImageToTetrahedralMeshFilter<LabelType>::New();
  mesher->SetInput(labels);
  mesher->SetScene(scene);
  mesher->Update();
  bmr::TetrahedralMesh         mesh = mesher->GetOutput()->Get();
  const bmr::ForwardSimulation sim = bmr::SimulateScene(scene, mesh);
  mesh.displacement = sim.displacement;
  std::cout << mesh << std::endl;
  auto meshObject = itk::TetrahedralMeshObject::New();
  meshObject->Set(mesh);

  using SourceType = itk::PhysicsDeformationFieldSource<FieldType>;
  auto pull = SourceType::New();
  pull->SetMesh(meshObject);
  pull->SetReferenceImage(labels);
  pull->Update();
  auto push = SourceType::New();
  push->SetMesh(meshObject);
  push->SetReferenceImage(labels);
  push->SetFieldDirection(SourceType::FieldDirectionEnum::MovingToFixed);
  push->Update();
  auto ctWarper = itk::ImageWarper<CTType, FieldType>::New();
  ctWarper->SetInput(ct);
  ctWarper->SetDisplacementField(pull->GetOutput());
  ctWarper->SetDefaultPixelValue(-1000.0f);
  ctWarper->Update();
  auto labelWarper = itk::ImageWarper<LabelType, FieldType>::New();
  labelWarper->SetInput(labels);
  labelWarper->SetDisplacementField(pull->GetOutput());
  labelWarper->Update();

  Write<FieldType>(pull->GetOutput(), prefix + "_field.nrrd");
  Write<FieldType>(push->GetOutput(), prefix + "_forward_field.nrrd");
  Write<CTType>(ctWarper->GetOutput(), prefix + "_warped_ct.nrrd");
  Write<LabelType>(labelWarper->GetOutput(), prefix + "_warped_labels.nrrd");
  const char * regenerate = std::getenv("BMR_WRITE_BASELINES");
  if (regenerate && std::string(regenerate) == "1")
  {
    Write<FieldType>(pull->GetOutput(), baseline + "/spheres_field.nrrd");
    Write<FieldType>(push->GetOutput(), baseline + "/spheres_forward_field.nrrd");
    Write<CTType>(ctWarper->GetOutput(), baseline + "/spheres_warped_ct.nrrd");
    Write<LabelType>(labelWarper->GetOutput(), baseline + "/spheres_warped_labels.nrrd");
    std::cout << "baselines written to " << baseline << std::endl;
    return EXIT_SUCCESS;
  }
  // Tolerances: 1e-6 mm on fields and 1e-3 HU on CT absorb the rounding differences of another BLAS
  // build while catching any change of mesh, physics or interpolation (which move values by >= 1e-3 mm).
  bool        ok = true;
  std::size_t differing = 0;
  for (const char * name : { "field", "forward_field" })
  {
    const FieldType * f = std::string(name) == "field" ? pull->GetOutput() : push->GetOutput();
    const double      d =
      MaxDifference<FieldType, double>(f, baseline + "/spheres_" + name + ".nrrd", VectorComponent, 3, differing, 1e-6);
    std::cout << name << ": max component difference " << d << " mm, " << differing << " voxels above 1e-6 mm"
              << std::endl;
    ok &= MatchesBaseline(name, d, differing, "1e-6 mm");
  }
  double d = MaxDifference<CTType, float>(
    ctWarper->GetOutput(), baseline + "/spheres_warped_ct.nrrd", Scalar, 1, differing, 1e-3);
  std::cout << "warped CT: max difference " << d << " HU, " << differing << " voxels above 1e-3 HU" << std::endl;
  ok &= MatchesBaseline("warped CT", d, differing, "1e-3 HU");
  d = MaxDifference<LabelType, std::int32_t>(
    labelWarper->GetOutput(), baseline + "/spheres_warped_labels.nrrd", Label, 1, differing, 0.5);
  std::cout << "warped labels: " << differing << " voxels differ" << std::endl;
  ok &= MatchesBaseline("warped labels", d, differing, "0.5");
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}
