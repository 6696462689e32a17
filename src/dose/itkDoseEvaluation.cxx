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
#include "itkDoseEvaluation.h"

#include "bmrAtomicFile.h"
#include "bmrError.h"
#include "itkGridGeometryConversion.h"
#include "itkIdentityTransform.h"
#include "itkImageRegionConstIterator.h"
#include "itkImageRegionConstIteratorWithIndex.h"
#include "itkImageRegionIterator.h"
#include "itkImageWarper.h"
#include "itkLinearInterpolateImageFunction.h"
#include "itkResampleImageFilter.h"
#include "itkSceneDistanceMaps.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

namespace itk {

namespace {

using DistanceMapType = Image<float, 3>;

/** Number of voxels of \a labels holding \a value. */
std::size_t
CountLabel(const DoseLabelImageType * labels, std::int32_t value)
{
  std::size_t count = 0;
  for (ImageRegionConstIterator<DoseLabelImageType> it(labels, labels->GetLargestPossibleRegion()); !it.IsAtEnd(); ++it)
  {
    count += it.Get() == value;
  }
  return count;
}

bool
SameGrid(const ImageBase<3> * a, const ImageBase<3> * b)
{
  const bmr::GridGeometry ga = GridGeometryOf(a);
  const bmr::GridGeometry gb = GridGeometryOf(b);
  for (unsigned int i = 0; i < 3; ++i)
  {
    if (ga.size[i] != gb.size[i] || std::abs(ga.origin[i] - gb.origin[i]) > 1e-6 ||
        std::abs(ga.spacing[i] - gb.spacing[i]) > 1e-6)
    {
      return false;
    }
  }
  for (unsigned int i = 0; i < 9; ++i)
  {
    if (std::abs(ga.direction[i] - gb.direction[i]) > 1e-9)
    {
      return false;
    }
  }
  return true;
}

/** Per voxel of \a labels (largest region, index 0 fastest): whether its center lies inside \a dose's grid as
 * the linear interpolator sees it (continuous index within [start - 0.5, end + 0.5] on every axis). */
std::vector<bool>
InsideDoseGrid(const DoseLabelImageType * labels, const BiomechanicalDoseImageType * dose)
{
  std::vector<bool> inside;
  inside.reserve(labels->GetLargestPossibleRegion().GetNumberOfPixels());
  const auto region = dose->GetLargestPossibleRegion();
  for (ImageRegionConstIteratorWithIndex<DoseLabelImageType> it(labels, labels->GetLargestPossibleRegion());
       !it.IsAtEnd();
       ++it)
  {
    Point<double, 3> point;
    labels->TransformIndexToPhysicalPoint(it.GetIndex(), point);
    ContinuousIndex<double, 3> index;
    dose->TransformPhysicalPointToContinuousIndex(point, index);
    bool in = true;
    for (unsigned int a = 0; a < 3; ++a)
    {
      const double start = static_cast<double>(region.GetIndex(a)) - 0.5;
      in = in && index[a] >= start && index[a] <= start + static_cast<double>(region.GetSize(a));
    }
    inside.push_back(in);
  }
  return inside;
}

/** The doses of one structure as they are gathered from the image. */
struct GatheredDoses
{
  std::vector<double> doses;
  std::size_t         outside{ 0 };
};

void
AddVoxelDose(GatheredDoses & structure, const std::string & name, float dose, bool insideGrid)
{
  if (!std::isfinite(dose) || dose < 0.0f)
  {
    std::ostringstream os;
    os << "the dose image holds " << dose << " Gy inside \"" << name << "\" (a dose must be finite and >= 0)";
    bmr::Fail("itk::EvaluateDose", os.str());
  }
  structure.doses.push_back(static_cast<double>(dose));
  structure.outside += !insideGrid;
}

std::string
Number(double value, int digits = 8)
{
  std::ostringstream os;
  os << std::setprecision(digits) << value;
  return os.str();
}

} // namespace

DoseMaskImageType::Pointer
AnteriorRectalWallMask(const DoseLabelImageType * labels,
                       std::int32_t               rectumLabel,
                       std::int32_t               prostateLabel,
                       double                     wallThicknessMm,
                       double                     prostateDistanceMm)
{
  const char * where = "itk::AnteriorRectalWallMask";
  if (labels == nullptr)
  {
    bmr::Fail(where, "no label image");
  }
  if (!(wallThicknessMm > 0.0) || !(prostateDistanceMm > 0.0))
  {
    bmr::Fail(where, "the wall thickness and the distance to the prostate [mm] must be positive");
  }
  for (const auto & organ : { std::make_pair(rectumLabel, "rectum"), std::make_pair(prostateLabel, "prostate") })
  {
    if (CountLabel(labels, organ.first) == 0)
    {
      bmr::Fail(where,
                std::string("the ") + organ.second + " label " + std::to_string(organ.first) +
                  " is absent from the label image");
    }
  }
  const auto rectumDistance = detail::FaceDistanceMap(labels, rectumLabel, rectumLabel);
  const auto prostateDistance = detail::FaceDistanceMap(labels, prostateLabel, prostateLabel);
  auto       mask = DoseMaskImageType::New();
  mask->CopyInformation(labels);
  mask->SetRegions(labels->GetLargestPossibleRegion());
  mask->Allocate(true);
  const auto                                   region = labels->GetLargestPossibleRegion();
  ImageRegionConstIterator<DoseLabelImageType> label(labels, region);
  ImageRegionConstIterator<DistanceMapType>    depth(rectumDistance, region);
  ImageRegionConstIterator<DistanceMapType>    toProstate(prostateDistance, region);
  ImageRegionIterator<DoseMaskImageType>       out(mask, region);
  for (; !label.IsAtEnd(); ++label, ++depth, ++toProstate, ++out)
  {
    // Inside the rectum the signed distance is minus the depth below its surface.
    const bool shell = label.Get() == rectumLabel && -depth.Get() <= wallThicknessMm;
    out.Set(shell && toProstate.Get() <= prostateDistanceMm ? 1 : 0);
  }
  return mask;
}

const StructureDose &
DoseEvaluation::Find(const std::string & name) const
{
  for (const auto & s : structures)
  {
    if (s.name == name)
    {
      return s;
    }
  }
  bmr::Fail("itk::DoseEvaluation::Find", "no structure \"" + name + "\" was evaluated");
}

std::map<std::string, std::int32_t>
DoseStructuresFromScene(const bmr::Scene & scene)
{
  std::map<std::string, std::int32_t> structures;
  for (const bmr::SceneLabel & label : scene.labels)
  {
    if (label.role != bmr::LabelRoleEnum::Outside)
    {
      structures[label.name] = label.value;
    }
  }
  return structures;
}

BiomechanicalDoseImageType::Pointer
ResampleDoseOntoGrid(const BiomechanicalDoseImageType * dose, const ImageBase<3> * reference)
{
  if (dose == nullptr || reference == nullptr)
  {
    bmr::Fail("itk::ResampleDoseOntoGrid", "no dose image or no reference grid");
  }
  if (SameGrid(dose, reference))
  {
    auto shared = BiomechanicalDoseImageType::New();
    shared->Graft(dose);
    return shared;
  }
  using ResampleType = ResampleImageFilter<BiomechanicalDoseImageType, BiomechanicalDoseImageType>;
  auto resample = ResampleType::New();
  resample->SetInput(dose);
  resample->SetTransform(IdentityTransform<double, 3>::New());
  resample->SetInterpolator(LinearInterpolateImageFunction<BiomechanicalDoseImageType, double>::New());
  resample->SetOutputParametersFromImage(reference);
  resample->SetDefaultPixelValue(0.0f);
  resample->Update();
  return resample->GetOutput();
}

namespace {

constexpr const char * EvaluateDoseWhere = "itk::EvaluateDose";

/** The structures evaluated, in order, with their label values (-1 for a derived one) and doses. */
struct StructureDoses
{
  std::vector<std::string>   names;
  std::vector<std::int32_t>  values;
  std::vector<GatheredDoses> gathered;
};

/** The doses of each of \a structures, from \a doseOnGrid on the grid of \a labels; \a inside: per voxel whether it
 * lies inside the dose grid (empty: all do). Throws when a structure is absent from \a labels. */
StructureDoses
GatherStructureDoses(const DoseLabelImageType *                  labels,
                     const BiomechanicalDoseImageType *          doseOnGrid,
                     const std::map<std::string, std::int32_t> & structures,
                     const std::vector<bool> &                   inside)
{
  // Structures by label value (several names may share one label).
  StructureDoses                           result;
  std::multimap<std::int32_t, std::size_t> byLabel;
  for (const auto & kv : structures)
  {
    byLabel.emplace(kv.second, result.names.size());
    result.names.push_back(kv.first);
    result.values.push_back(kv.second);
  }
  result.gathered.resize(result.names.size());
  ImageRegionConstIterator<DoseLabelImageType>         label(labels, labels->GetLargestPossibleRegion());
  ImageRegionConstIterator<BiomechanicalDoseImageType> doseIt(doseOnGrid, doseOnGrid->GetLargestPossibleRegion());
  for (std::size_t voxel = 0; !label.IsAtEnd(); ++label, ++doseIt, ++voxel)
  {
    const auto range = byLabel.equal_range(label.Get());
    for (auto s = range.first; s != range.second; ++s)
    {
      AddVoxelDose(result.gathered[s->second], result.names[s->second], doseIt.Get(), inside.empty() || inside[voxel]);
    }
  }
  for (std::size_t s = 0; s < result.names.size(); ++s)
  {
    if (result.gathered[s].doses.empty())
    {
      bmr::Fail(EvaluateDoseWhere,
                "structure \"" + result.names[s] + "\" (label " + std::to_string(result.values[s]) +
                  ") is absent from the label image");
    }
  }
  return result;
}

/** The doses of the anterior rectal wall between the labels \a rectumLabel and \a prostateLabel. Throws when it is
 * empty. */
GatheredDoses
GatherAnteriorRectalWallDoses(const DoseLabelImageType *         labels,
                              const BiomechanicalDoseImageType * doseOnGrid,
                              std::int32_t                       rectumLabel,
                              std::int32_t                       prostateLabel,
                              const AnteriorRectalWallSettings & settings,
                              const std::vector<bool> &          inside)
{
  const auto wall =
    AnteriorRectalWallMask(labels, rectumLabel, prostateLabel, settings.wallThicknessMm, settings.prostateDistanceMm);
  GatheredDoses                                        wallDoses;
  ImageRegionConstIterator<DoseMaskImageType>          in(wall, labels->GetLargestPossibleRegion());
  ImageRegionConstIterator<BiomechanicalDoseImageType> d(doseOnGrid, doseOnGrid->GetLargestPossibleRegion());
  for (std::size_t voxel = 0; !in.IsAtEnd(); ++in, ++d, ++voxel)
  {
    if (in.Get())
    {
      AddVoxelDose(wallDoses, settings.name, d.Get(), inside.empty() || inside[voxel]);
    }
  }
  if (wallDoses.doses.empty())
  {
    bmr::Fail(EvaluateDoseWhere,
              "the anterior rectal wall is empty: no voxel of \"" + settings.rectumName + "\" lies within " +
                Number(settings.prostateDistanceMm) + " mm of \"" + settings.prostateName + "\"");
  }
  return wallDoses;
}

/** The metrics and DVH of each structure of \a doses, of voxels of \a voxelVolume [mm^3]. */
std::vector<StructureDose>
EvaluateStructureDoses(const StructureDoses & doses, double voxelVolume, const DoseEvaluationSettings & settings)
{
  // One dose axis for every DVH: up to the largest dose of any structure.
  double maximumDose = 0.0;
  for (const auto & g : doses.gathered)
  {
    maximumDose = std::max(maximumDose, *std::max_element(g.doses.begin(), g.doses.end()));
  }
  std::vector<StructureDose> evaluated;
  for (std::size_t s = 0; s < doses.names.size(); ++s)
  {
    const auto    found = settings.eudParameters.find(doses.names[s]);
    const double  a = found != settings.eudParameters.end() ? found->second : bmr::DefaultEudParameter(doses.names[s]);
    const auto &  gathered = doses.gathered[s].doses;
    StructureDose result;
    result.name = doses.names[s];
    result.label = doses.values[s];
    result.metrics = bmr::ComputeDoseMetrics(gathered, voxelVolume, a, settings.volumeDosesGy);
    result.dvh = bmr::ComputeDoseVolumeHistogram(gathered, voxelVolume, settings.binWidthGy, maximumDose);
    result.fractionOutsideDoseGrid =
      static_cast<double>(doses.gathered[s].outside) / static_cast<double>(gathered.size());
    evaluated.push_back(std::move(result));
  }
  return evaluated;
}

} // namespace

DoseEvaluation
EvaluateDose(const DoseLabelImageType *                  labels,
             const BiomechanicalDoseImageType *          dose,
             const std::map<std::string, std::int32_t> & structures,
             const DoseEvaluationSettings &              settings)
{
  if (labels == nullptr || dose == nullptr)
  {
    bmr::Fail(EvaluateDoseWhere, "no label image or no dose image");
  }
  if (structures.empty())
  {
    bmr::Fail(EvaluateDoseWhere, "no structures to evaluate");
  }
  DoseEvaluation evaluation;
  evaluation.binWidthGy = settings.binWidthGy;
  evaluation.volumeDosesGy = settings.volumeDosesGy;
  evaluation.doseResampled = !SameGrid(dose, labels);
  const auto              doseOnGrid = ResampleDoseOntoGrid(dose, labels);
  const std::vector<bool> inside = evaluation.doseResampled ? InsideDoseGrid(labels, dose) : std::vector<bool>();
  StructureDoses          doses = GatherStructureDoses(labels, doseOnGrid, structures, inside);

  const auto rectum = structures.find(settings.wall.rectumName);
  const auto prostate = structures.find(settings.wall.prostateName);
  if (settings.anteriorRectalWall && rectum != structures.end() && prostate != structures.end())
  {
    GatheredDoses wallDoses =
      GatherAnteriorRectalWallDoses(labels, doseOnGrid, rectum->second, prostate->second, settings.wall, inside);
    doses.names.push_back(settings.wall.name);
    doses.values.push_back(-1);
    doses.gathered.push_back(std::move(wallDoses));
  }
  const auto & spacing = labels->GetSpacing();
  const double voxelVolume = spacing[0] * spacing[1] * spacing[2];
  evaluation.structures = EvaluateStructureDoses(doses, voxelVolume, settings);
  return evaluation;
}

std::string
DoseVolumeHistogramCsv(const DoseEvaluation & evaluation)
{
  std::ostringstream os;
  os << "dose_Gy";
  for (const auto & s : evaluation.structures)
  {
    os << "," << s.name << "_cumulative_pct";
  }
  for (const auto & s : evaluation.structures)
  {
    os << "," << s.name << "_differential_pct";
  }
  os << "\n";
  const std::size_t bins = evaluation.structures.empty() ? 0 : evaluation.structures.front().dvh.cumulative.size();
  for (std::size_t k = 0; k < bins; ++k)
  {
    os << Number(evaluation.structures.front().dvh.BinDose(k), 10);
    for (const auto & s : evaluation.structures)
    {
      os << "," << Number(100.0 * s.dvh.cumulative[k]);
    }
    for (const auto & s : evaluation.structures)
    {
      os << "," << Number(100.0 * s.dvh.differential[k]);
    }
    os << "\n";
  }
  return os.str();
}

std::string
DoseMetricsCsv(const DoseEvaluation & evaluation)
{
  std::ostringstream os;
  os << "organ,a,gEUD_Gy,Dmean_Gy,D95_Gy,D2_Gy,D98_Gy,Dmin_Gy,Dmax_Gy";
  for (const double v : evaluation.volumeDosesGy)
  {
    os << ",V" << Number(v) << "Gy_pct";
  }
  os << ",volume_cc,voxels,outside_dose_grid_pct\n";
  for (const auto & s : evaluation.structures)
  {
    const bmr::DoseMetrics & m = s.metrics;
    os << s.name << "," << Number(m.eudA) << "," << Number(m.gEUD) << "," << Number(m.mean) << "," << Number(m.D95)
       << "," << Number(m.D2) << "," << Number(m.D98) << "," << Number(m.minimum) << "," << Number(m.maximum);
    for (const auto & v : m.volumesAtDose)
    {
      os << "," << Number(100.0 * v.fraction);
    }
    os << "," << Number(m.volumeCC) << "," << m.numberOfVoxels << "," << Number(100.0 * s.fractionOutsideDoseGrid)
       << "\n";
  }
  return os.str();
}

void
WriteDoseEvaluation(const std::string & directory, const DoseEvaluation & evaluation)
{
  // Both tables are formed before either file is written.
  const std::string dvh = DoseVolumeHistogramCsv(evaluation);
  const std::string metrics = DoseMetricsCsv(evaluation);
  bmr::WriteTextFileAtomically(directory + "/dvh.csv", dvh);
  bmr::WriteTextFileAtomically(directory + "/dose_metrics.csv", metrics);
}

double
PenumbraSigma(double penumbraMm)
{
  if (!(penumbraMm > 0.0) || !std::isfinite(penumbraMm))
  {
    bmr::Fail("itk::PenumbraSigma", "the penumbra [mm] must be positive and finite");
  }
  // Phi^{-1}(0.8): the 80 % and 20 % levels of Phi(-d / sigma) lie at d = -/+ 0.8416 sigma.
  constexpr double probit80 = 0.8416212335729143;
  return penumbraMm / (2.0 * probit80);
}

BiomechanicalDoseImageType::Pointer
MakeConformalDosePlan(const DoseLabelImageType *    labels,
                      std::int32_t                  prostateLabel,
                      const ConformalPlanSettings & settings)
{
  const char * where = "itk::MakeConformalDosePlan";
  if (labels == nullptr)
  {
    bmr::Fail(where, "no label image");
  }
  const ConformalPlanSettings & p = settings;
  if (!(p.marginMm >= 0.0 && p.marginMm <= 50.0) || !(p.prescriptionGy > 0.0) || !std::isfinite(p.prescriptionGy) ||
      !(p.bathFraction >= 0.0 && p.bathFraction < 1.0) || !(p.bathLengthMm > 0.0))
  {
    std::ostringstream os;
    os << "settings out of range: margin " << p.marginMm << " mm (0-50), prescription " << p.prescriptionGy
       << " Gy (> 0), bath fraction " << p.bathFraction << " ([0, 1)), bath length " << p.bathLengthMm << " mm (> 0)";
    bmr::Fail(where, os.str());
  }
  const double sigma = PenumbraSigma(p.penumbraMm);
  if (CountLabel(labels, prostateLabel) == 0)
  {
    bmr::Fail(where, "the prostate label " + std::to_string(prostateLabel) + " is absent from the label image");
  }
  // The map is overwritten in place by the dose: same grid, one buffer.
  auto              plan = detail::FaceDistanceMap(labels, prostateLabel, prostateLabel);
  float *           value = plan->GetBufferPointer();
  const std::size_t n = plan->GetBufferedRegion().GetNumberOfPixels();
  const double      scale = 1.0 / (std::sqrt(2.0) * sigma);
  for (std::size_t i = 0; i < n; ++i)
  {
    const double d = static_cast<double>(value[i]) - p.marginMm; // signed distance to the PTV surface [mm]
    double       fraction = 0.5 * std::erfc(d * scale);
    if (p.bathFraction > 0.0)
    {
      fraction += p.bathFraction * (1.0 - fraction) * std::exp(-std::max(d, 0.0) / p.bathLengthMm);
    }
    value[i] = static_cast<float>(p.prescriptionGy * fraction);
  }
  return plan;
}

BiomechanicalDoseImageType::Pointer
WarpDose(const BiomechanicalDoseImageType * dose, const DoseDisplacementFieldType * field)
{
  if (dose == nullptr || field == nullptr)
  {
    bmr::Fail("itk::WarpDose", "no dose image or no displacement field");
  }
  return WarpImage(dose, field, false, 0.0f);
}

} // namespace itk
