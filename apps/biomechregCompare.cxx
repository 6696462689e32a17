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
// biomechreg compare: physics-based registration against the Demons baseline and the identity on seed
// landmarks, per image pair and across pairs (paired t-test, as dissertation Table 3.5).
// biomechreg phantom-set: N reproducible pelvis phantom pairs for it.
#include "biomechregCommon.h"
#include "bmrLandmarks.h"
#include "bmrStatistics.h"
#include "itkCheckerBoardImageFilter.h"
#include "itkExtractImageFilter.h"
#include "itkImplantedSeedDetection.h"
#include "itkIntensityWindowingImageFilter.h"
#include "itkLandmarkRegistrationError.h"
#include "itkRegistrationQualityMeasures.h"

#include <fstream>
#include <random>

namespace bmrcli {
namespace {

/** One line of the pair list: paths, relative ones resolved against the list's directory. */
struct PairInputs
{
  std::string                        name;
  std::map<std::string, std::string> paths; ///< column -> path ("" when absent)
};

const std::vector<std::string> RequiredColumns = { "name",     "moving_ct",    "moving_labels",
                                                   "fixed_ct", "fixed_labels", "scene" };
const std::vector<std::string> OptionalColumns = { "moving_landmarks", "fixed_landmarks", "fem_field", "demons_field" };

std::string
Resolve(const std::string & base, const std::string & path)
{
  return path.empty() || path[0] == '/' ? path : base + "/" + path;
}

std::vector<PairInputs>
ReadPairList(const std::string & path)
{
  std::ifstream in(path);
  if (!in)
  {
    throw std::runtime_error("cannot open the pair list \"" + path + "\"");
  }
  const std::size_t        slash = path.find_last_of('/');
  const std::string        base = slash == std::string::npos ? "." : path.substr(0, slash);
  std::vector<std::string> header;
  std::vector<PairInputs>  pairs;
  std::string              line;
  std::size_t              number = 0;
  while (std::getline(in, line))
  {
    ++number;
    if (!line.empty() && line.back() == '\r')
    {
      line.pop_back();
    }
    if (line.empty() || line[0] == '#')
    {
      continue;
    }
    std::vector<std::string> fields;
    std::istringstream       row(line);
    std::string              field;
    while (std::getline(row, field, ','))
    {
      fields.push_back(field);
    }
    if (line.back() == ',')
    {
      fields.emplace_back();
    }
    if (header.empty())
    {
      header = fields;
      for (const auto & c : RequiredColumns)
      {
        if (std::find(header.begin(), header.end(), c) == header.end())
        {
          throw std::runtime_error("pair list \"" + path + "\": the header lacks the column \"" + c + "\"");
        }
      }
      for (const auto & c : header)
      {
        if (std::find(RequiredColumns.begin(), RequiredColumns.end(), c) == RequiredColumns.end() &&
            std::find(OptionalColumns.begin(), OptionalColumns.end(), c) == OptionalColumns.end())
        {
          throw std::runtime_error("pair list \"" + path + "\": unknown column \"" + c + "\"");
        }
      }
      continue;
    }
    if (fields.size() != header.size())
    {
      throw std::runtime_error("pair list \"" + path + "\" line " + std::to_string(number) + ": " +
                               std::to_string(fields.size()) + " fields, the header has " +
                               std::to_string(header.size()));
    }
    PairInputs p;
    for (std::size_t i = 0; i < header.size(); ++i)
    {
      if (header[i] == "name")
      {
        p.name = fields[i];
      }
      else
      {
        p.paths[header[i]] = Resolve(base, fields[i]);
      }
    }
    if (p.name.empty() || p.name.find_first_of("/\\ ") != std::string::npos)
    {
      throw std::runtime_error("pair list \"" + path + "\" line " + std::to_string(number) +
                               ": the name must be non-empty, without spaces or slashes");
    }
    for (std::size_t c = 1; c < RequiredColumns.size(); ++c)
    {
      if (p.paths[RequiredColumns[c]].empty())
      {
        throw std::runtime_error("pair list \"" + path + "\" line " + std::to_string(number) + ": the column \"" +
                                 RequiredColumns[c] + "\" is empty");
      }
    }
    for (const auto & other : pairs)
    {
      if (other.name == p.name)
      {
        throw std::runtime_error("pair list \"" + path + "\": the name \"" + p.name + "\" appears twice");
      }
    }
    pairs.push_back(p);
  }
  if (pairs.empty())
  {
    throw std::runtime_error("pair list \"" + path + "\" holds no image pair");
  }
  return pairs;
}

/** What one method gave on one pair. */
struct MethodResult
{
  std::string                                           method;
  double                                                seconds{ 0.0 }; ///< compute time, writing excluded
  bool                                                  precomputed{ false };
  std::vector<double>                                   tre;     ///< mm, in the order of the fixed landmarks
  std::map<std::string, itk::LabelOverlap>              overlap; ///< per organ
  std::map<std::string, itk::SurfaceDistanceStatistics> surface; ///< per organ, mm
  itk::JacobianDeterminantStatistics                    jacobian;
};

struct CompareOptions
{
  std::vector<std::string> methods{ "identity", "fem", "demons" };
  std::string              tag{ "default" };
  std::string              seedOrgan; ///< "" : the scene's first unknown material
  std::string              flatten;   ///< "" : the seed organ
  DemonsSettings           demons;
  RegisterInputs           fem; ///< settings only
};

/** The seed landmarks of a pair: from the listed files, or detected in both CTs and paired. */
void
PairLandmarks(const PairInputs &           pair,
              const CTImageType *          movingCT,
              const LabelImageType *       movingLabels,
              const CTImageType *          fixedCT,
              const LabelImageType *       fixedLabels,
              std::int32_t                 organ,
              const std::string &          dir,
              std::vector<bmr::Landmark> & moving,
              std::vector<bmr::Landmark> & fixed)
{
  const std::string movingPath = pair.paths.count("moving_landmarks") ? pair.paths.at("moving_landmarks") : "";
  const std::string fixedPath = pair.paths.count("fixed_landmarks") ? pair.paths.at("fixed_landmarks") : "";
  if (!movingPath.empty() && !fixedPath.empty())
  {
    moving = bmr::ReadLandmarks(movingPath);
    fixed = bmr::ReadLandmarks(fixedPath);
    return;
  }
  moving = itk::DetectImplantedSeeds(movingCT, movingLabels, organ);
  fixed = itk::DetectImplantedSeeds(fixedCT, fixedLabels, organ);
  if (moving.empty() || moving.size() != fixed.size())
  {
    throw std::runtime_error("pair \"" + pair.name + "\": found " + std::to_string(moving.size()) +
                             " seeds in the moving CT and " + std::to_string(fixed.size()) +
                             " in the fixed CT (give landmark files instead)");
  }
  const auto                 match = bmr::MatchLandmarks(moving, fixed);
  std::vector<bmr::Landmark> paired(fixed.size());
  for (std::size_t i = 0; i < moving.size(); ++i)
  {
    paired[i] = { moving[i].id, fixed[match[i]].point };
  }
  fixed = paired;
  bmr::WriteLandmarks(dir + "/seeds_moving.csv", moving);
  bmr::WriteLandmarks(dir + "/seeds_fixed.csv", fixed);
}

/** Writes a 4 x 4 checkerboard of the fixed CT and a warped CT on the axial slice through \a centre
 * (soft-tissue window -200 ... 300 HU), as dissertation Fig. 3.12. */
void
WriteCheckerboard(const CTImageType *           fixed,
                  const CTImageType *           warped,
                  const itk::Point<double, 3> & centre,
                  const std::string &           path)
{
  using SliceType = itk::Image<float, 2>;
  using PngType = itk::Image<unsigned char, 2>;
  itk::Index<3> index;
  fixed->TransformPhysicalPointToIndex(centre, index);
  auto region = fixed->GetLargestPossibleRegion();
  index[2] = std::max<itk::IndexValueType>(region.GetIndex(2),
                                           std::min<itk::IndexValueType>(index[2], region.GetUpperIndex()[2]));
  region.SetIndex(2, index[2]);
  region.SetSize(2, 0);
  SliceType::Pointer  slices[2];
  const CTImageType * images[2] = { fixed, warped };
  for (int i = 0; i < 2; ++i)
  {
    auto extract = itk::ExtractImageFilter<CTImageType, SliceType>::New();
    extract->SetInput(images[i]);
    extract->SetExtractionRegion(region);
    extract->SetDirectionCollapseToIdentity();
    extract->Update();
    slices[i] = extract->GetOutput();
  }
  auto board = itk::CheckerBoardImageFilter<SliceType>::New();
  board->SetInput1(slices[0]);
  board->SetInput2(slices[1]);
  itk::FixedArray<unsigned int, 2> pattern;
  pattern.Fill(4);
  board->SetCheckerPattern(pattern);
  auto window = itk::IntensityWindowingImageFilter<SliceType, PngType>::New();
  window->SetInput(board->GetOutput());
  window->SetWindowMinimum(-200.0f);
  window->SetWindowMaximum(300.0f);
  window->SetOutputMinimum(0);
  window->SetOutputMaximum(255);
  window->Update();
  WriteImage<PngType>(window->GetOutput(), path);
}

/** Scores a field: TRE on the landmarks, overlap and surface distances of the organs, Jacobian. */
void
Score(MethodResult &                     r,
      const FieldType *                  field,
      const LabelImageType *             movingLabels,
      const LabelImageType *             fixedLabels,
      const bmr::Scene &                 scene,
      const std::vector<bmr::Landmark> & movingLandmarks,
      const std::vector<bmr::Landmark> & fixedLandmarks)
{
  r.tre = itk::ComputeTargetRegistrationErrors(field, fixedLandmarks, movingLandmarks);
  const auto warped = Warp<LabelImageType>(movingLabels, field, true, 0);
  for (const auto & term : scene.objective)
  {
    const bmr::SceneLabel * l = scene.FindLabel(term.label);
    r.overlap[l->name] = itk::ComputeLabelOverlap<LabelImageType>(warped, fixedLabels, l->value);
    if (r.overlap[l->name].inA > 0 && r.overlap[l->name].inB > 0)
    {
      r.surface[l->name] = itk::ComputeSurfaceDistances<LabelImageType>(warped, fixedLabels, l->value);
    }
  }
  r.jacobian = itk::ComputeJacobianDeterminantStatistics(field);
}

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

int
CompareCommand(const Arguments & args)
{
  const std::string listPath = args.Require("--pairs");
  const std::string out = args.Require("--out");
  CompareOptions    o;
  o.methods.clear();
  {
    std::istringstream in(args.Get("--methods", "identity,fem,demons"));
    std::string        m;
    while (std::getline(in, m, ','))
    {
      if (m != "identity" && m != "fem" && m != "demons")
      {
        throw UsageError("--methods takes identity, fem and demons (comma-separated), not \"" + m + "\"");
      }
      o.methods.push_back(m);
    }
  }
  o.tag = args.Get("--tag", o.tag);
  o.seedOrgan = args.Get("--seed-organ");
  o.flatten = args.Get("--flatten");
  o.demons = ParseDemonsSettings(args);
  ParseFemSettings(args, o.fem);
  args.CheckAllUsed();
  // Every input is checked before anything is written: a bad list leaves no partial output.
  const std::vector<PairInputs> pairs = ReadPairList(listPath);
  for (const PairInputs & pair : pairs)
  {
    for (const auto & kv : pair.paths)
    {
      struct stat info;
      if (!kv.second.empty() && stat(kv.second.c_str(), &info) != 0)
      {
        throw std::runtime_error("pair \"" + pair.name + "\": " + kv.first + " \"" + kv.second + "\" does not exist");
      }
    }
    bmr::ReadScene(pair.paths.at("scene"));
  }
  MakeDirectory(out);

  std::ostringstream perLandmark, perPair, perOrgan;
  perLandmark << "# target registration error per landmark [mm]\npair,method,tag,landmark,tre_mm\n";
  perPair << "# one row per pair and method; lengths in mm, time in s (compute only, writing excluded)\n"
          << "pair,method,tag,seconds,landmarks,tre_mean_mm,tre_sd_mm,tre_max_mm,dice_mean,msd_mean_mm,hd95_mean_mm,"
             "jacobian_min,jacobian_fraction_nonpositive,jacobian_sd_log\n";
  perOrgan << "# per organ after warping the moving labels; surface distances in mm\n"
           << "pair,method,tag,organ,dice,msd_mm,hd95_mm,hausdorff_mm\n";
  std::map<std::string, std::vector<double>> treAll, treMeans;
  std::ostringstream                         table;
  table << "| pair | method | seeds | TRE mean ± SD [mm] | TRE max [mm] | Dice (mean of organs) | HD95 [mm] | "
           "min J | J ≤ 0 | time [s] |\n|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n";

  for (const PairInputs & pair : pairs)
  {
    std::cout << "\n=== pair " << pair.name << " ===" << std::endl;
    const std::string dir = out + "/" + pair.name;
    MakeDirectory(dir);
    StageTimer timer;
    timer.Begin("read inputs");
    const bmr::Scene scene = bmr::ReadScene(pair.paths.at("scene"));
    auto             movingCT = ReadImage<CTImageType>(pair.paths.at("moving_ct"), "moving CT");
    auto             movingLabels = ReadImage<LabelImageType>(pair.paths.at("moving_labels"), "moving label image");
    auto             fixedCT = ReadImage<CTImageType>(pair.paths.at("fixed_ct"), "fixed CT");
    auto             fixedLabels = ReadImage<LabelImageType>(pair.paths.at("fixed_labels"), "fixed label image");
    timer.End();

    std::string organName = o.seedOrgan;
    for (const auto & l : scene.labels)
    {
      if (organName.empty() && l.role == bmr::LabelRole::UnknownMaterial)
      {
        organName = l.name;
      }
    }
    const bmr::SceneLabel * organ = scene.FindLabel(organName);
    if (!organ)
    {
      throw std::runtime_error("pair \"" + pair.name + "\": no seed organ (give --seed-organ NAME of the scene)");
    }
    timer.Begin("landmarks");
    std::vector<bmr::Landmark> movingLandmarks, fixedLandmarks;
    PairLandmarks(
      pair, movingCT, movingLabels, fixedCT, fixedLabels, organ->value, dir, movingLandmarks, fixedLandmarks);
    timer.End(std::to_string(fixedLandmarks.size()) + " pairs");
    const std::vector<std::int32_t> flatten = ParseLabelList(o.flatten.empty() ? organName : o.flatten, &scene);

    // Centre of the checkerboard slice: the seeds' centroid in the fixed image.
    itk::Point<double, 3> centre;
    centre.Fill(0.0);
    for (const auto & l : fixedLandmarks)
    {
      for (int a = 0; a < 3; ++a)
      {
        centre[a] += l.point[a] / double(fixedLandmarks.size());
      }
    }

    for (const std::string & method : o.methods)
    {
      MethodResult       r;
      FieldType::Pointer field;
      r.method = method;
      const std::string given = pair.paths.count(method + "_field") ? pair.paths.at(method + "_field") : "";
      const auto        start = Clock::now();
      if (!given.empty())
      {
        field = ReadImage<FieldType>(given, method + " field");
        r.precomputed = true;
      }
      else if (method == "identity")
      {
        field = FieldType::New();
        field->CopyInformation(fixedCT);
        field->SetRegions(fixedCT->GetLargestPossibleRegion());
        field->Allocate(true);
      }
      else if (method == "fem")
      {
        RegisterInputs in = o.fem;
        in.scene = scene;
        in.movingLabels = movingLabels;
        in.fixedLabels = fixedLabels;
        in.movingCT = movingCT;
        in.out = dir + "/fem";
        StageTimer fem;
        field = RunRegistration(in, fem).pullBack;
        for (const auto & s : fem.stages)
        {
          // Compute time only: writing compressed outputs is the same for every method and not part of it.
          r.seconds += s.first.rfind("write", 0) == 0 ? 0.0 : s.second;
        }
      }
      else
      {
        std::cout << "  Demons (" << o.demons.variant << ", " << o.demons.levels << " levels x " << o.demons.iterations
                  << " iterations, flattened labels: " << (o.flatten.empty() ? organName : o.flatten) << ") ..."
                  << std::flush;
        field = RunDemons(fixedCT, movingCT, fixedLabels, movingLabels, flatten, o.demons);
        r.seconds = std::chrono::duration<double>(Clock::now() - start).count();
        std::cout << " " << Fixed(r.seconds, 1) << " s" << std::endl;
        MakeDirectory(dir + "/demons");
        WriteImage<FieldType>(field, dir + "/demons/field.nrrd");
      }
      if (method == "identity")
      {
        r.seconds = 0.0;
      }
      Score(r, field, movingLabels, fixedLabels, scene, movingLandmarks, fixedLandmarks);
      const auto warpedCT = Warp<CTImageType>(movingCT, field, false, -1000.0f);
      WriteCheckerboard(fixedCT, warpedCT, centre, dir + "/checkerboard_" + method + ".png");

      const bmr::SummaryStatistics tre = bmr::Summarize(r.tre);
      std::vector<double>          dice, msd, hd95;
      for (const auto & kv : r.overlap)
      {
        dice.push_back(kv.second.dice);
        const auto s = r.surface.find(kv.first);
        perOrgan << pair.name << "," << method << "," << o.tag << "," << kv.first << "," << kv.second.dice;
        if (s != r.surface.end())
        {
          msd.push_back(s->second.mean);
          hd95.push_back(s->second.percentile95);
          perOrgan << "," << s->second.mean << "," << s->second.percentile95 << "," << s->second.maximum << "\n";
        }
        else
        {
          perOrgan << ",,,\n";
        }
      }
      for (std::size_t i = 0; i < r.tre.size(); ++i)
      {
        perLandmark << pair.name << "," << method << "," << o.tag << "," << fixedLandmarks[i].id << "," << r.tre[i]
                    << "\n";
        treAll[method].push_back(r.tre[i]);
      }
      treMeans[method].push_back(tre.mean);
      perPair << pair.name << "," << method << "," << o.tag << "," << (r.precomputed ? "" : std::to_string(r.seconds))
              << "," << r.tre.size() << "," << tre.mean << "," << tre.standardDeviation << "," << tre.maximum << ","
              << Mean(dice) << "," << Mean(msd) << "," << Mean(hd95) << "," << r.jacobian.minimum << ","
              << r.jacobian.fractionNonPositive << "," << r.jacobian.standardDeviationOfLog << "\n";
      table << "| " << pair.name << " | " << method << " | " << r.tre.size() << " | " << Fixed(tre.mean, 2) << " ± "
            << Fixed(tre.standardDeviation, 2) << " | " << Fixed(tre.maximum, 2) << " | " << Fixed(Mean(dice), 4)
            << " | " << Fixed(Mean(hd95), 2) << " | " << Fixed(r.jacobian.minimum, 3) << " | "
            << Fixed(100.0 * r.jacobian.fractionNonPositive, 3) << " % | "
            << (r.precomputed ? std::string("given") : Fixed(r.seconds, 1)) << " |\n";
      std::cout << "  " << std::left << std::setw(9) << method << std::right << " TRE " << Fixed(tre.mean, 2) << " ± "
                << Fixed(tre.standardDeviation, 2) << " mm (max " << Fixed(tre.maximum, 2) << "), Dice "
                << Fixed(Mean(dice), 4) << ", HD95 " << Fixed(Mean(hd95), 2) << " mm, min J "
                << Fixed(r.jacobian.minimum, 3) << ", " << Fixed(r.seconds, 1) << " s" << std::endl;
    }
  }

  std::ostringstream md;
  md << "# Registration comparison on seed landmarks (tag: " << o.tag << ")\n\n"
     << "TRE: target registration error of the seed landmarks under each fixed → moving field [mm]; "
        "Dice and HD95 (95th percentile of the symmetric surface distance) averaged over the scene's objective "
        "organs; J: Jacobian determinant of the field. Time: compute only [s].\n\n"
     << table.str() << "\n## Paired two-tailed t-tests on TRE (FEM − other)\n\n"
     << "| comparison | n | mean difference [mm] | t | p | p < 0.05 |\n|---|---:|---:|---:|---:|---|\n";
  std::ostringstream tests;
  tests << "comparison,unit,n,mean_difference_mm,t,p\n";
  for (const std::string other : { "demons", "identity" })
  {
    if (!treAll.count("fem") || !treAll.count(other))
    {
      continue;
    }
    md << TTestRow("FEM vs " + other + ", every seed", treAll["fem"], treAll[other])
       << TTestRow("FEM vs " + other + ", pair means", treMeans["fem"], treMeans[other]);
    for (int unit = 0; unit < 2; ++unit)
    {
      const auto & a = unit ? treMeans["fem"] : treAll["fem"];
      const auto & b = unit ? treMeans[other] : treAll[other];
      if (a.size() >= 2)
      {
        const auto t = bmr::PairedTTest(a, b);
        tests << "fem_vs_" << other << "," << (unit ? "pair_mean" : "seed") << "," << t.count << "," << t.meanDifference
              << "," << t.t << "," << t.pValue << "\n";
      }
    }
  }
  bmr::WriteTextFileAtomically(out + "/per_landmark.csv", perLandmark.str());
  bmr::WriteTextFileAtomically(out + "/per_pair.csv", perPair.str());
  bmr::WriteTextFileAtomically(out + "/per_organ.csv", perOrgan.str());
  bmr::WriteTextFileAtomically(out + "/ttests.csv", tests.str());
  bmr::WriteTextFileAtomically(out + "/summary.md", md.str());
  std::cout << "\n"
            << md.str() << "\nWrote " << out
            << "/{summary.md, per_pair.csv, per_organ.csv, per_landmark.csv, ttests.csv, <pair>/checkerboard_*.png}"
            << "\n(plots: /usr/bin/python3 scripts/plot_compare.py " << out << ")" << std::endl;
  return EXIT_SUCCESS;
}

int
PhantomSetCommand(const Arguments & args)
{
  const std::string out = args.Require("--out");
  const double      count = args.Number("--count", 5);
  const double      seed = args.Number("--seed", 1);
  if (!(count >= 1 && count <= 100 && count == std::floor(count)) || !(seed >= 0 && seed == std::floor(seed)))
  {
    throw UsageError("--count must be an integer in [1, 100] and --seed a non-negative integer");
  }
  args.CheckAllUsed();
  MakeDirectory(out);
  // Reproducible draws: std::mt19937_64's sequence is fixed by the standard (its distributions are not,
  // so the uniform numbers are made from the raw integers).
  std::mt19937_64 rng(static_cast<std::uint64_t>(seed));
  const auto      uniform = [&rng](double lo, double hi) {
    return lo + (hi - lo) * (double(rng() >> 11) / double(std::uint64_t(1) << 53));
  };
  std::ostringstream list, parameters;
  list << "# pelvis phantom pairs with ground-truth seed landmarks (biomechreg phantom-set)\n"
       << "name,moving_ct,moving_labels,fixed_ct,fixed_labels,scene,moving_landmarks,fixed_landmarks\n";
  parameters << "name,true_E_kPa,bladder_mm,rectum_mm,seed\n";
  for (unsigned int k = 0; k < static_cast<unsigned int>(count); ++k)
  {
    PhantomOptions    o;
    const std::string name = "pair" + std::to_string(k + 1);
    o.out = out + "/" + name;
    o.grid = bmr::PelvisPhantomParameters().grid;
    o.prostateE = std::round(std::exp(uniform(std::log(50.0), std::log(300.0))));
    o.bladderMM = std::round(100.0 * uniform(3.0, 8.0)) / 100.0;
    o.rectumMM = std::round(100.0 * uniform(2.0, 5.0)) / 100.0;
    o.seed = static_cast<std::uint64_t>(seed) * 1000 + k + 1;
    std::cout << "\n"
              << name << ": prostate " << o.prostateE << " kPa, bladder +" << o.bladderMM << " mm, rectum +"
              << o.rectumMM << " mm, seed " << o.seed << std::endl;
    StageTimer timer;
    MakePhantom(o, timer);
    list << name << "," << name << "/moving_ct.nrrd," << name << "/moving_labels.nrrd," << name << "/fixed_ct.nrrd,"
         << name << "/fixed_labels.nrrd," << name << "/scene.json," << name << "/landmarks_moving.csv," << name
         << "/landmarks_fixed.csv\n";
    parameters << name << "," << o.prostateE << "," << o.bladderMM << "," << o.rectumMM << "," << o.seed << "\n";
  }
  bmr::WriteTextFileAtomically(out + "/pairs.csv", list.str());
  bmr::WriteTextFileAtomically(out + "/phantom_set.csv", parameters.str());
  std::cout << "\nWrote " << out << "/pairs.csv (for biomechreg compare --pairs) and phantom_set.csv" << std::endl;
  return EXIT_SUCCESS;
}

} // namespace bmrcli
