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
#include "itkBiomechanicalWriters.h"

#include "bmrAtomicFile.h"
#include "bmrError.h"
#include "bmrNpzWriter.h"
#include "bmrStopwatch.h"
#include "bmrVtuWriter.h"
#include "itkBiomechanicalImageIO.h"
#include "itkBiomechanicalReports.h"
#include "itkCastImageFilter.h"
#include "itkImageRegionConstIteratorWithIndex.h"

#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <sstream>

namespace itk {

void
MakeOutputDirectory(const std::string & path)
{
  std::error_code error;
  std::filesystem::create_directories(path, error);
  if (error || !std::filesystem::is_directory(path))
  {
    bmr::Fail("MakeOutputDirectory", "cannot create output directory \"" + path + "\"");
  }
}

void
WriteSimulationMesh(const std::string & path, const SimulationResult & s)
{
  if (s.simulation.vonMises.size() != s.mesh.GetNumberOfTetrahedra())
  {
    bmr::Fail("WriteSimulationMesh",
              "cannot write \"" + path +
                "\": the state has no per-element moduli and stress (computed when "
                "RegistrationSettings::elementState is on)");
  }
  const std::vector<double> dirichlet(s.simulation.dirichlet.begin(), s.simulation.dirichlet.end());
  const std::vector<double> labels(s.mesh.labels.begin(), s.mesh.labels.end());
  bmr::WriteVtu(
    path,
    s.mesh,
    { { "displacement", 3, s.mesh.displacement }, { "force", 3, s.mesh.force }, { "dirichlet", 1, dirichlet } },
    { { "label", 1, labels },
      { "youngs_modulus", 1, s.simulation.youngsModulus },
      { "poisson_ratio", 1, s.simulation.poissonRatio },
      { "von_mises", 1, s.simulation.vonMises } });
}

void
WriteSimulationOutputs(const std::string &                 directory,
                       const SimulationResult &            s,
                       const BiomechanicalLabelImageType * warpedLabels,
                       const BiomechanicalCTImageType *    warpedCT)
{
  MakeOutputDirectory(directory);
  WriteSimulationMesh(directory + "/mesh.vtu", s);
  WriteImageAtomically(s.pullBack.GetPointer(), directory + "/field.nrrd");
  if (s.push)
  {
    WriteImageAtomically(s.push.GetPointer(), directory + "/forward_field.nrrd");
  }
  WriteImageAtomically(warpedLabels, directory + "/warped_labels.nrrd");
  if (warpedCT)
  {
    WriteImageAtomically(warpedCT, directory + "/warped_ct.nrrd");
  }
}

RegistrationOutputs
RegistrationOutputs::All()
{
  RegistrationOutputs o;
  o.forwardField = o.mesh = o.history = o.sweep = true;
  return o;
}

RegistrationOutputs
RegistrationOutputs::Parse(const std::string & list)
{
  using Flag = bool                   RegistrationOutputs::*;
  const std::pair<const char *, Flag> items[] = {
    { "field", &RegistrationOutputs::field },        { "forward_field", &RegistrationOutputs::forwardField },
    { "warped_ct", &RegistrationOutputs::warpedCT }, { "warped_labels", &RegistrationOutputs::warpedLabels },
    { "mesh", &RegistrationOutputs::mesh },          { "history", &RegistrationOutputs::history },
    { "sweep", &RegistrationOutputs::sweep },        { "report", &RegistrationOutputs::report },
    { "field_npz", &RegistrationOutputs::fieldNpz }
  };
  RegistrationOutputs o;
  for (const auto & item : items)
  {
    o.*item.second = false;
  }
  std::stringstream in(list);
  for (std::string name; std::getline(in, name, ',');)
  {
    // "all" and "default" stand for their sets, alone or with more items ("default,history").
    const bool          isSet = name == "all" || name == "default";
    RegistrationOutputs set = name == "all" ? All() : RegistrationOutputs();
    bool                known = isSet;
    for (const auto & [item, flag] : items)
    {
      if (isSet ? set.*flag : name == item)
      {
        o.*flag = known = true;
      }
    }
    if (!known)
    {
      bmr::Fail("RegistrationOutputs",
                "unknown output \"" + name +
                  "\" (outputs: field, forward_field, warped_ct, warped_labels, mesh, history, sweep, report, "
                  "field_npz, all, default)");
    }
  }
  return o;
}

namespace {
/** A displacement field at the precision asked for. */
void
WriteField(const BiomechanicalFieldType * field, const std::string & path, const RegistrationOutputs & o)
{
  if (o.doubleFields)
  {
    WriteImageAtomically(field, path, o.compressionLevel);
    return;
  }
  using FloatFieldType = Image<Vector<float, 3>, 3>;
  auto cast = CastImageFilter<BiomechanicalFieldType, FloatFieldType>::New();
  cast->SetInput(field);
  cast->Update();
  WriteImageAtomically(cast->GetOutput(), path, o.compressionLevel);
}
} // namespace

PipelineStage
WriteRegistrationOutputs(const std::string &                directory,
                         const RegistrationResult &         result,
                         const RegistrationSettings &       settings,
                         const std::vector<PipelineStage> & stages,
                         const RegistrationOutputs &        o)
{
  const auto start = bmr::SteadyClock::now();
  if (o.forwardField && !result.state.push)
  {
    bmr::Fail("WriteRegistrationOutputs",
              "forward_field asked for, but the push field was not computed "
              "(RegistrationSettings::pushField)");
  }
  MakeOutputDirectory(directory);
  if (o.mesh)
  {
    WriteSimulationMesh(directory + "/mesh.vtu", result.state);
  }
  if (o.field)
  {
    WriteField(result.state.pullBack.GetPointer(), directory + "/field.nrrd", o);
  }
  if (o.forwardField)
  {
    WriteField(result.state.push.GetPointer(), directory + "/forward_field.nrrd", o);
  }
  if (o.fieldNpz)
  {
    WriteLearn2RegDisplacement(
      result.state.pullBack.GetPointer(), result.movingGrid.GetPointer(), directory + "/field.npz");
  }
  if (o.warpedLabels)
  {
    WriteImageAtomically(result.warpedLabels.GetPointer(), directory + "/warped_labels.nrrd", o.compressionLevel);
  }
  if (o.warpedCT && result.warpedCT)
  {
    WriteImageAtomically(result.warpedCT.GetPointer(), directory + "/warped_ct.nrrd", o.compressionLevel);
  }
  std::vector<std::string> unknownNames;
  for (const auto & u : result.unknowns)
  {
    unknownNames.push_back(u.name);
  }
  if (o.history)
  {
    auto history = result.estimation.history;
    history.insert(history.end(), result.estimation.outerIterations.begin(), result.estimation.outerIterations.end());
    bmr::WriteTextFileAtomically(directory + "/history.csv", IterationHistoryCsv(history, unknownNames));
  }
  if (o.sweep && !result.estimation.sweep.empty())
  {
    bmr::WriteTextFileAtomically(directory + "/sweep.csv", IterationHistoryCsv(result.estimation.sweep, unknownNames));
  }
  const PipelineStage writing{ "write outputs", bmr::SecondsSince(start) };
  if (o.report)
  {
    std::vector<PipelineStage> wallTimes = stages;
    wallTimes.push_back(writing);
    bmr::WriteTextFileAtomically(directory + "/report.json", RegistrationReportJson(result, settings, wallTimes));
  }
  return writing;
}

namespace {
/** origin, spacing and direction (row-major) of \a grid as float64 arrays "<prefix>_origin", ... */
std::vector<bmr::NpyArray>
GridArrays(const std::string & prefix, const ImageBase<3> * grid)
{
  std::vector<double> origin(3), spacing(3), direction(9);
  for (unsigned int r = 0; r < 3; ++r)
  {
    origin[r] = grid->GetOrigin()[r];
    spacing[r] = grid->GetSpacing()[r];
    for (unsigned int c = 0; c < 3; ++c)
    {
      direction[3 * r + c] = grid->GetDirection()(r, c);
    }
  }
  return { bmr::NpyArray::Float64(prefix + "_origin", origin, { 3 }),
           bmr::NpyArray::Float64(prefix + "_spacing", spacing, { 3 }),
           bmr::NpyArray::Float64(prefix + "_direction", direction, { 3, 3 }) };
}
} // namespace

void
WriteLearn2RegDisplacement(const BiomechanicalFieldType * field,
                           const ImageBase<3> *           movingGrid,
                           const std::string &            path)
{
  if (field == nullptr || movingGrid == nullptr)
  {
    bmr::FailInput("WriteLearn2RegDisplacement", "cannot write \"" + path + "\": no field or no moving grid");
  }
  const auto &  region = field->GetLargestPossibleRegion();
  const auto    size = region.GetSize();
  bmr::NpyArray disp{ "disp", "<f4", { 3, size[0], size[1], size[2] }, true, {} };
  disp.bytes.resize(3 * sizeof(float) * region.GetNumberOfPixels());
  char * out = disp.bytes.data();
  for (ImageRegionConstIteratorWithIndex<BiomechanicalFieldType> it(field, region); !it.IsAtEnd(); ++it)
  {
    Point<double, 3> x;
    field->TransformIndexToPhysicalPoint(it.GetIndex(), x);
    const auto & u = it.Get();
    if (!(std::isfinite(u[0]) && std::isfinite(u[1]) && std::isfinite(u[2])))
    {
      std::ostringstream os;
      os << "cannot write \"" << path << "\": the field at voxel " << it.GetIndex() << " is not finite";
      bmr::FailInput("WriteLearn2RegDisplacement", os.str());
    }
    const auto moving = movingGrid->TransformPhysicalPointToContinuousIndex<double, double>(x + u);
    for (unsigned int c = 0; c < 3; ++c) // ITK's order: component, then x fastest: Fortran order of (3, nx, ny, nz)
    {
      const auto value = static_cast<float>(moving[c] - double(it.GetIndex()[c] - region.GetIndex()[c]));
      std::memcpy(out, &value, sizeof(float));
      out += sizeof(float);
    }
  }
  std::vector<bmr::NpyArray> arrays{ std::move(disp) };
  for (auto & a : GridArrays("fixed", field))
  {
    arrays.push_back(std::move(a));
  }
  for (auto & a : GridArrays("moving", movingGrid))
  {
    arrays.push_back(std::move(a));
  }
  bmr::WriteNpz(path, arrays);
}

void
WritePhantomPair(const std::string & directory, const PhantomPair & pair, const PhantomSettings & settings)
{
  MakeOutputDirectory(directory);
  WriteImageAtomically(pair.movingCT.GetPointer(), directory + "/moving_ct.nrrd");
  WriteImageAtomically(pair.movingLabels.GetPointer(), directory + "/moving_labels.nrrd");
  WriteImageAtomically(pair.fixedCT.GetPointer(), directory + "/fixed_ct.nrrd");
  WriteImageAtomically(pair.fixedLabels.GetPointer(), directory + "/fixed_labels.nrrd");
  for (const auto & kv : pair.fixedFractions)
  {
    WriteImageAtomically(kv.second.GetPointer(), directory + "/fixed_fraction_" + kv.first + ".nrrd");
  }
  for (const auto & kv : pair.fixedContourFractions)
  {
    WriteImageAtomically(kv.second.GetPointer(), directory + "/fixed_outline_fraction_" + kv.first + ".nrrd");
  }
  WriteImageAtomically(pair.truthField.GetPointer(), directory + "/truth_field.nrrd");
  bmr::WriteTextFileAtomically(directory + "/scene.json", bmr::SceneToJson(pair.scene));
  bmr::WriteTextFileAtomically(directory + "/truth_scene.json", bmr::SceneToJson(pair.truthScene));
  if (!pair.movingLandmarks.empty())
  {
    bmr::WriteLandmarks(directory + "/" + pair.scene.movingLandmarks, pair.movingLandmarks);
    bmr::WriteLandmarks(directory + "/" + pair.scene.fixedLandmarks, pair.fixedLandmarks);
    bmr::WriteLandmarks(directory + "/landmarks_tracked.csv", pair.trackedLandmarks);
  }
  bmr::WriteTextFileAtomically(directory + "/truth.json", PhantomTruthJson(pair, settings));
}

} // namespace itk
