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
// Benchmark of the pull-back rasterization on the demo pair (not a test: wall-clock numbers only).
//
//   bmrRasterizationBenchmark make CACHE           phantom pair of the demo (200 x 160 x 160 voxels of 1 mm),
//                                                  meshed at the estimation scene's sizes and simulated with the
//                                                  truth's loads and moduli; writes mesh + grid to CACHE
//   bmrRasterizationBenchmark run CACHE [R] [T]    R runs (default 5) of PhysicsDeformationFieldSource with T
//                                                  work units (default 2): every time, the median and an FNV-1a
//                                                  hash of the field's bytes (bit-identity before/after)
//   bmrRasterizationBenchmark parts CACHE [R]      one thread: the rasterizer's set-up, its scan, the fill
//
// Time it under the benchmark lock (flock /tmp/bmr-bench.lock ...); count instructions with
// valgrind --tool=callgrind ... run CACHE 1 1.
#include "bmrDisplacementFieldRasterizer.h"
#include "bmrHash.h"
#include "itkBiomechanicalPipelines.h"
#include "itkGridGeometryConversion.h"
#include "itkPhysicsDeformationFieldSource.h"

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <string>
#include <vector>

namespace {
using FieldType = itk::Image<itk::Vector<double, 3>, 3>;
using SourceType = itk::PhysicsDeformationFieldSource<FieldType>;

struct Case
{
  bmr::GridGeometry    grid;
  bmr::TetrahedralMesh mesh;
};

template<typename T>
void
WriteVector(std::ofstream & out, const std::vector<T> & v)
{
  const std::uint64_t n = v.size();
  out.write(reinterpret_cast<const char *>(&n), sizeof(n));
  out.write(reinterpret_cast<const char *>(v.data()), static_cast<std::streamsize>(n * sizeof(T)));
}

template<typename T>
void
ReadVector(std::ifstream & in, std::vector<T> & v)
{
  std::uint64_t n = 0;
  in.read(reinterpret_cast<char *>(&n), sizeof(n));
  v.resize(n);
  in.read(reinterpret_cast<char *>(v.data()), static_cast<std::streamsize>(n * sizeof(T)));
}

void
WriteCase(const std::string & path, const Case & c)
{
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char *>(&c.grid), sizeof(c.grid));
  WriteVector(out, c.mesh.points);
  WriteVector(out, c.mesh.tetrahedra);
  WriteVector(out, c.mesh.labels);
  WriteVector(out, c.mesh.displacement);
}

Case
ReadCase(const std::string & path)
{
  std::ifstream in(path, std::ios::binary);
  if (!in)
  {
    throw std::runtime_error("cannot read " + path);
  }
  Case c;
  in.read(reinterpret_cast<char *>(&c.grid), sizeof(c.grid));
  ReadVector(in, c.mesh.points);
  ReadVector(in, c.mesh.tetrahedra);
  ReadVector(in, c.mesh.labels);
  ReadVector(in, c.mesh.displacement);
  return c;
}

int
Make(const std::string & path)
{
  // The demo's phantom (apps/biomechreg.cxx DemoCommand).
  itk::PhantomSettings o;
  o.grid.size = { { 200, 160, 160 } };
  o.grid.spacing = { { 1.0, 1.0, 1.0 } };
  o.bladderMM = 8.0;
  o.rectumMM = 4.0;
  o.prostateE = 100.0;
  const itk::PhantomPair pair = itk::MakePhantomPair(o);
  // The registration's mesh (the estimation scene's sizes) with the truth's loads and moduli.
  bmr::Scene scene = pair.truthScene;
  scene.mesh = pair.scene.mesh;
  const itk::SimulationResult sim = itk::SimulateLabelImage(pair.movingLabels, scene, pair.fixedLabels, nullptr, false);
  Case                        c;
  c.grid = itk::GridGeometryOf(pair.fixedLabels.GetPointer());
  c.mesh = sim.mesh;
  WriteCase(path, c);
  std::cout << "wrote " << path << ": " << c.mesh.GetNumberOfTetrahedra() << " tetrahedra, "
            << c.mesh.GetNumberOfPoints() << " nodes, grid " << c.grid.size[0] << " x " << c.grid.size[1] << " x "
            << c.grid.size[2] << std::endl;
  return EXIT_SUCCESS;
}

itk::Image<float, 3>::Pointer
Reference(const bmr::GridGeometry & grid)
{
  auto                      image = itk::Image<float, 3>::New();
  itk::ImageRegion<3>       region;
  itk::Vector<double, 3>    spacing;
  itk::Point<double, 3>     origin;
  itk::Matrix<double, 3, 3> direction;
  for (unsigned int i = 0; i < 3; ++i)
  {
    region.SetSize(i, grid.size[i]);
    spacing[i] = grid.spacing[i];
    origin[i] = grid.origin[i];
    for (unsigned int j = 0; j < 3; ++j)
    {
      direction(i, j) = grid.direction[3 * i + j];
    }
  }
  image->SetRegions(region);
  image->SetSpacing(spacing);
  image->SetOrigin(origin);
  image->SetDirection(direction);
  return image; // never allocated: only its geometry is used
}


double
Seconds(std::chrono::steady_clock::time_point since)
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

double
Median(std::vector<double> v)
{
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

void
PrintTimes(const char * what, const std::vector<double> & t)
{
  std::cout << what << ": median " << std::fixed << std::setprecision(3) << Median(t) << " s (";
  for (std::size_t i = 0; i < t.size(); ++i)
  {
    std::cout << (i ? " " : "") << t[i];
  }
  std::cout << ")" << std::endl;
}

int
Run(const std::string & path, int runs, int threads)
{
  const Case c = ReadCase(path);
  auto       meshObject = itk::TetrahedralMeshObject::New();
  meshObject->Set(c.mesh);
  const auto          reference = Reference(c.grid);
  std::vector<double> times;
  std::uint64_t       hash = 0;
  for (int r = 0; r < runs; ++r)
  {
    auto source = SourceType::New();
    source->SetMesh(meshObject);
    source->SetReferenceImage(reference);
    source->SetNumberOfWorkUnits(threads);
    source->GetMultiThreader()->SetMaximumNumberOfThreads(threads);
    const auto start = std::chrono::steady_clock::now();
    source->Update();
    times.push_back(Seconds(start));
    const FieldType *   field = source->GetOutput();
    const std::uint64_t h = bmr::Fnv1a(field->GetBufferPointer(),
                                       field->GetPixelContainer()->Size() * sizeof(FieldType::PixelType),
                                       1469598103934665603ULL);
    if (r > 0 && h != hash)
    {
      std::cout << "run " << r << ": the field differs from run 0" << std::endl;
    }
    hash = h;
    if (r == 0)
    {
      std::cout << c.mesh.GetNumberOfTetrahedra() << " tetrahedra, " << c.grid.GetNumberOfVoxels() << " voxels, "
                << source->GetNumberOfCoveredVoxels() << " covered, " << source->GetNumberOfInvertedElements()
                << " inverted, " << threads << " work units" << std::endl;
    }
  }
  PrintTimes("pull-back field", times);
  std::cout << "fnv1a " << std::hex << std::setw(16) << std::setfill('0') << hash << std::dec << std::endl;
  return EXIT_SUCCESS;
}

int
Parts(const std::string & path, int runs)
{
  const Case          c = ReadCase(path);
  const std::size_t   nvox = c.grid.GetNumberOfVoxels();
  std::vector<double> setup, allocate, scan, fill;
  for (int r = 0; r < runs; ++r)
  {
    auto                                   start = std::chrono::steady_clock::now();
    const bmr::DisplacementFieldRasterizer rasterizer(
      c.mesh, c.mesh.displacement, c.grid, bmr::FieldKindEnum::PullBack);
    setup.push_back(Seconds(start));
    start = std::chrono::steady_clock::now();
    std::vector<double>        field(3 * nvox, 0.0);
    std::vector<unsigned char> inside(nvox, 0);
    allocate.push_back(Seconds(start));
    start = std::chrono::steady_clock::now();
    rasterizer.RasterizeRegion({ { 0, 0, 0 } }, c.grid.size, field.data(), inside.data());
    scan.push_back(Seconds(start));
    start = std::chrono::steady_clock::now();
    bmr::FillOutsideHarmonic(c.grid, field.data(), inside.data(), 4);
    fill.push_back(Seconds(start));
  }
  PrintTimes("set-up (element inverses)", setup);
  PrintTimes("allocate + zero buffers", allocate);
  PrintTimes("element scan (1 thread)", scan);
  PrintTimes("harmonic fill", fill);
  return EXIT_SUCCESS;
}
} // namespace

int
main(int argc, char * argv[])
{
  try
  {
    const std::string mode = argc > 2 ? argv[1] : "";
    if (mode == "make")
    {
      return Make(argv[2]);
    }
    if (mode == "run")
    {
      return Run(argv[2], argc > 3 ? std::atoi(argv[3]) : 5, argc > 4 ? std::atoi(argv[4]) : 2);
    }
    if (mode == "parts")
    {
      return Parts(argv[2], argc > 3 ? std::atoi(argv[3]) : 5);
    }
    std::cerr << "usage: " << argv[0] << " make CACHE | run CACHE [RUNS] [THREADS] | parts CACHE [RUNS]" << std::endl;
    return 2;
  }
  catch (const std::exception & e)
  {
    std::cerr << "error: " << e.what() << std::endl;
    return EXIT_FAILURE;
  }
}
