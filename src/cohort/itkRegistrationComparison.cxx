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
#include "itkRegistrationComparison.h"

#include "bmrCsvTable.h"
#include "bmrError.h"
#include "bmrStatistics.h"
#include "itkBiomechanicalImageIO.h"
#include "itkCheckerBoardImageFilter.h"
#include "itkExtractImageFilter.h"
#include "itkImageWarper.h"
#include "itkImplantedSeedDetection.h"
#include "itkIntensityWindowingImageFilter.h"
#include "itkLandmarkRegistrationError.h"

#include <algorithm>
#include <fstream>
#include <iomanip>
#include <sstream>

namespace itk {
namespace {
const std::vector<std::string> RequiredColumns = { "name",     "moving_ct",    "moving_labels",
                                                   "fixed_ct", "fixed_labels", "scene" };
const std::vector<std::string> OptionalColumns = { "moving_landmarks", "fixed_landmarks", "fem_field", "demons_field" };


double
Mean(const std::vector<double> & v)
{
  return v.empty() ? 0.0 : bmr::Summarize(v).mean;
}

std::string
Fixed(double v, int digits)
{
  std::ostringstream o;
  o << std::fixed << std::setprecision(digits) << v;
  return o.str();
}

/** The t-test line of the summary (two-tailed, paired). */
std::string
TTestRow(const std::string & what, const std::vector<double> & a, const std::vector<double> & b)
{
  if (a.size() < 2)
  {
    return "| " + what + " | " + std::to_string(a.size()) + " | – | – | – | (fewer than 2 pairs) |\n";
  }
  const auto         t = bmr::PairedTTest(a, b);
  std::ostringstream o;
  o << "| " << what << " | " << t.count << " | " << Fixed(t.meanDifference, 3) << " | " << Fixed(t.t, 3) << " | "
    << std::scientific << std::setprecision(3) << t.pValue << " | " << (t.pValue < 0.05 ? "yes" : "no") << " |\n";
  return o.str();
}

} // namespace

std::vector<ImagePairEntry>
ReadImagePairList(const std::string & path)
{
  const bmr::CsvTable table = bmr::CsvTable::Read(path, "pair list");
  table.CheckColumns(RequiredColumns, OptionalColumns);
  std::vector<ImagePairEntry> pairs;
  for (const bmr::CsvRow & row : table.Rows())
  {
    ImagePairEntry p;
    p.name = table.Field(row, "name");
    if (p.name.empty() || p.name.find_first_of("/\\ ") != std::string::npos)
    {
      table.FailAt(row, "name", "the name must be non-empty, without spaces or slashes");
    }
    for (const auto & column : table.Columns())
    {
      if (column != "name")
      {
        p.paths[column] = table.ResolvePath(table.Field(row, column));
      }
    }
    for (std::size_t c = 1; c < RequiredColumns.size(); ++c)
    {
      if (p.paths[RequiredColumns[c]].empty())
      {
        table.FailAt(row, RequiredColumns[c], "is empty");
      }
    }
    for (const auto & other : pairs)
    {
      if (other.name == p.name)
      {
        table.FailAt(row, "name", "the name \"" + p.name + "\" appears twice");
      }
    }
    pairs.push_back(p);
  }
  if (pairs.empty())
  {
    table.Fail("holds no image pair");
  }
  return pairs;
}

/** Writes a 4 x 4 checkerboard of the fixed CT and a warped CT on the axial slice through \a center
 * (soft-tissue window -200 ... 300 HU), as dissertation Fig. 3.12. */
void
WriteCheckerboardPNG(const BiomechanicalCTImageType * fixed,
                     const BiomechanicalCTImageType * warped,
                     const Point<double, 3> &         center,
                     const std::string &              path)
{
  using SliceType = Image<float, 2>;
  using PngType = Image<unsigned char, 2>;
  Index<3> index;
  fixed->TransformPhysicalPointToIndex(center, index);
  auto region = fixed->GetLargestPossibleRegion();
  index[2] =
    std::max<IndexValueType>(region.GetIndex(2), std::min<IndexValueType>(index[2], region.GetUpperIndex()[2]));
  region.SetIndex(2, index[2]);
  region.SetSize(2, 0);
  SliceType::Pointer               slices[2];
  const BiomechanicalCTImageType * images[2] = { fixed, warped };
  for (int i = 0; i < 2; ++i)
  {
    auto extract = ExtractImageFilter<BiomechanicalCTImageType, SliceType>::New();
    extract->SetInput(images[i]);
    extract->SetExtractionRegion(region);
    extract->SetDirectionCollapseToIdentity();
    extract->Update();
    slices[i] = extract->GetOutput();
  }
  auto board = CheckerBoardImageFilter<SliceType>::New();
  board->SetInput1(slices[0]);
  board->SetInput2(slices[1]);
  FixedArray<unsigned int, 2> pattern;
  pattern.Fill(4);
  board->SetCheckerPattern(pattern);
  auto window = IntensityWindowingImageFilter<SliceType, PngType>::New();
  window->SetInput(board->GetOutput());
  window->SetWindowMinimum(-200.0f);
  window->SetWindowMaximum(300.0f);
  window->SetOutputMinimum(0);
  window->SetOutputMaximum(255);
  window->Update();
  WriteImageAtomically<PngType>(window->GetOutput(), path);
}

FieldEvaluation
EvaluateField(const BiomechanicalFieldType *      field,
              const BiomechanicalLabelImageType * movingLabels,
              const BiomechanicalLabelImageType * fixedLabels,
              const bmr::Scene &                  scene,
              const std::vector<bmr::Landmark> &  movingLandmarks,
              const std::vector<bmr::Landmark> &  fixedLandmarks)
{
  FieldEvaluation r;
  r.tre = ComputeTargetRegistrationErrors(field, fixedLandmarks, movingLandmarks);
  const auto warped = WarpImage(movingLabels, field, true, 0);
  const auto overlaps = ComputeLabelOverlaps<BiomechanicalLabelImageType>(warped, fixedLabels);
  for (const auto & term : scene.objective)
  {
    const bmr::SceneLabel * l = scene.FindLabel(term.label);
    const auto              found = overlaps.find(l->value);
    r.overlap[l->name] = found == overlaps.end() ? LabelOverlap() : found->second;
    if (r.overlap[l->name].inA > 0 && r.overlap[l->name].inB > 0)
    {
      r.surface[l->name] = ComputeSurfaceDistances<BiomechanicalLabelImageType>(warped, fixedLabels, l->value);
    }
  }
  r.jacobian = ComputeJacobianDeterminantStatistics(field);
  return r;
}

void
DetectPairedSeeds(const BiomechanicalCTImageType *    movingCT,
                  const BiomechanicalLabelImageType * movingLabels,
                  const BiomechanicalCTImageType *    fixedCT,
                  const BiomechanicalLabelImageType * fixedLabels,
                  std::int32_t                        organ,
                  const std::string &                 what,
                  std::vector<bmr::Landmark> &        moving,
                  std::vector<bmr::Landmark> &        fixed)
{
  moving = DetectImplantedSeeds(movingCT, movingLabels, organ);
  fixed = DetectImplantedSeeds(fixedCT, fixedLabels, organ);
  if (moving.empty() || moving.size() != fixed.size())
  {
    bmr::Fail("DetectPairedSeeds",
              what + ": found " + std::to_string(moving.size()) + " seeds in the moving CT and " +
                std::to_string(fixed.size()) + " in the fixed CT (give landmark files instead)");
  }
  const auto                 match = bmr::MatchLandmarks(moving, fixed);
  std::vector<bmr::Landmark> paired(fixed.size());
  for (std::size_t i = 0; i < moving.size(); ++i)
  {
    paired[i] = { moving[i].id, fixed[match[i]].point };
  }
  fixed = paired;
}

namespace {
/** Mean Dice, mean surface distance and mean HD95 over the organs of an evaluation. */
struct OrganMeans
{
  double dice{ 0.0 }, msd{ 0.0 }, hd95{ 0.0 };
};

OrganMeans
MeansOverOrgans(const FieldEvaluation & e)
{
  std::vector<double> dice, msd, hd95;
  for (const auto & kv : e.overlap)
  {
    dice.push_back(kv.second.dice);
    const auto s = e.surface.find(kv.first);
    if (s != e.surface.end())
    {
      msd.push_back(s->second.mean);
      hd95.push_back(s->second.percentile95);
    }
  }
  return { Mean(dice), Mean(msd), Mean(hd95) };
}
} // namespace

ComparisonTables::ComparisonTables(std::string tag)
  : m_Tag(std::move(tag))
{}

void
ComparisonTables::Add(const std::string &                pair,
                      const std::string &                method,
                      double                             seconds,
                      const std::vector<bmr::Landmark> & fixedLandmarks,
                      const FieldEvaluation &            r)
{
  std::ostringstream landmarks, pairs, organs, table;
  for (const auto & kv : r.overlap)
  {
    const auto s = r.surface.find(kv.first);
    organs << pair << "," << method << "," << m_Tag << "," << kv.first << "," << kv.second.dice;
    if (s != r.surface.end())
    {
      organs << "," << s->second.mean << "," << s->second.percentile95 << "," << s->second.maximum << "\n";
    }
    else
    {
      organs << ",,,\n";
    }
  }
  for (std::size_t i = 0; i < r.tre.size(); ++i)
  {
    landmarks << pair << "," << method << "," << m_Tag << "," << fixedLandmarks[i].id << "," << r.tre[i] << "\n";
    m_TreAll[method].push_back(r.tre[i]);
  }
  const bmr::SummaryStatistics tre = bmr::Summarize(r.tre);
  const OrganMeans             means = MeansOverOrgans(r);
  m_TreMeans[method].push_back(tre.mean);
  pairs << pair << "," << method << "," << m_Tag << "," << (seconds < 0.0 ? "" : std::to_string(seconds)) << ","
        << r.tre.size() << "," << tre.mean << "," << tre.standardDeviation << "," << tre.maximum << "," << means.dice
        << "," << means.msd << "," << means.hd95 << "," << r.jacobian.minimum << "," << r.jacobian.fractionNonPositive
        << "," << r.jacobian.standardDeviationOfLog << "\n";
  table << "| " << pair << " | " << method << " | " << r.tre.size() << " | " << Fixed(tre.mean, 2) << " ± "
        << Fixed(tre.standardDeviation, 2) << " | " << Fixed(tre.maximum, 2) << " | " << Fixed(means.dice, 4) << " | "
        << Fixed(means.hd95, 2) << " | " << Fixed(r.jacobian.minimum, 3) << " | "
        << Fixed(100.0 * r.jacobian.fractionNonPositive, 3) << " % | "
        << (seconds < 0.0 ? std::string("given") : Fixed(seconds, 1)) << " |\n";
  m_PerLandmark += landmarks.str();
  m_PerPair += pairs.str();
  m_PerOrgan += organs.str();
  m_Table += table.str();
}

std::string
ComparisonTables::Summary(const FieldEvaluation & r, double seconds)
{
  const bmr::SummaryStatistics tre = bmr::Summarize(r.tre);
  const OrganMeans             means = MeansOverOrgans(r);
  return "TRE " + Fixed(tre.mean, 2) + " ± " + Fixed(tre.standardDeviation, 2) + " mm (max " + Fixed(tre.maximum, 2) +
         "), Dice " + Fixed(means.dice, 4) + ", HD95 " + Fixed(means.hd95, 2) + " mm, min J " +
         Fixed(r.jacobian.minimum, 3) + ", " + Fixed(std::max(seconds, 0.0), 1) + " s";
}

std::string
ComparisonTables::PerLandmarkCsv() const
{
  return "# target registration error per landmark [mm]\npair,method,tag,landmark,tre_mm\n" + m_PerLandmark;
}

std::string
ComparisonTables::PerPairCsv() const
{
  return "# one row per pair and method; lengths in mm, time in s (compute only, writing excluded)\n"
         "pair,method,tag,seconds,landmarks,tre_mean_mm,tre_sd_mm,tre_max_mm,dice_mean,msd_mean_mm,hd95_mean_mm,"
         "jacobian_min,jacobian_fraction_nonpositive,jacobian_sd_log\n" +
         m_PerPair;
}

std::string
ComparisonTables::PerOrganCsv() const
{
  return "# per organ after warping the moving labels; surface distances in mm\n"
         "pair,method,tag,organ,dice,msd_mm,hd95_mm,hausdorff_mm\n" +
         m_PerOrgan;
}

std::string
ComparisonTables::TTestsCsv() const
{
  std::ostringstream tests;
  tests << "comparison,unit,n,mean_difference_mm,t,p\n";
  for (const std::string other : { "demons", "identity" })
  {
    if (!m_TreAll.count("fem") || !m_TreAll.count(other))
    {
      continue;
    }
    for (int unit = 0; unit < 2; ++unit)
    {
      const auto & a = unit ? m_TreMeans.at("fem") : m_TreAll.at("fem");
      const auto & b = unit ? m_TreMeans.at(other) : m_TreAll.at(other);
      if (a.size() >= 2)
      {
        const auto t = bmr::PairedTTest(a, b);
        tests << "fem_vs_" << other << "," << (unit ? "pair_mean" : "seed") << "," << t.count << "," << t.meanDifference
              << "," << t.t << "," << t.pValue << "\n";
      }
    }
  }
  return tests.str();
}

std::string
ComparisonTables::SummaryMarkdown() const
{
  std::ostringstream md;
  md << "# Registration comparison on seed landmarks (tag: " << m_Tag << ")\n\n"
     << "TRE: target registration error of the seed landmarks under each fixed → moving field [mm]; "
        "Dice and HD95 (95th percentile of the symmetric surface distance) averaged over the scene's objective "
        "organs; J: Jacobian determinant of the field. Time: compute only [s].\n\n"
     << "| pair | method | seeds | TRE mean ± SD [mm] | TRE max [mm] | Dice (mean of organs) | HD95 [mm] | "
        "min J | J ≤ 0 | time [s] |\n|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n"
     << m_Table << "\n## Paired two-tailed t-tests on TRE (FEM − other)\n\n"
     << "| comparison | n | mean difference [mm] | t | p | p < 0.05 |\n|---|---:|---:|---:|---:|---|\n";
  for (const std::string other : { "demons", "identity" })
  {
    if (m_TreAll.count("fem") && m_TreAll.count(other))
    {
      md << TTestRow("FEM vs " + other + ", every seed", m_TreAll.at("fem"), m_TreAll.at(other))
         << TTestRow("FEM vs " + other + ", pair means", m_TreMeans.at("fem"), m_TreMeans.at(other));
    }
  }
  return md.str();
}

} // namespace itk
