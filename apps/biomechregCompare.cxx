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
#include "itkRegistrationComparison.h"

#include <cmath>

namespace bmrcli {
namespace {

struct CompareOptions
{
  std::vector<std::string>  methods{ "identity", "fem", "demons" };
  std::string               tag{ "default" };
  std::string               seedOrgan; ///< "" : the scene's first unknown material
  std::string               flatten;   ///< "" : the seed organ
  itk::DemonsSettings       demons;
  itk::RegistrationSettings fem;
};

CompareOptions
ParseCompareOptions(const Arguments & args)
{
  CompareOptions     o;
  std::istringstream in(args.Get("--methods", "identity,fem,demons"));
  o.methods.clear();
  for (std::string m; std::getline(in, m, ',');)
  {
    if (m != "identity" && m != "fem" && m != "demons")
    {
      throw UsageError("--methods takes identity, fem and demons (comma-separated), not \"" + m + "\"");
    }
    o.methods.push_back(m);
  }
  o.tag = args.Get("--tag", o.tag);
  o.seedOrgan = args.Get("--seed-organ");
  o.flatten = args.Get("--flatten");
  o.demons = ParseDemonsSettings(args);
  const bool uncertaintyAsked = args.Has("--uncertainty");
  o.fem = ParseRegistrationSettings(args);
  if (!uncertaintyAsked)
  {
    // compare scores fields, not moduli: no resamples unless asked for.
    o.fem.uncertainty.method = itk::UncertaintyMethodEnum::None;
  }
  return o;
}

/** The images, scene and landmarks of one pair. */
struct PairData
{
  bmr::Scene                 scene;
  CTImageType::Pointer       movingCT, fixedCT;
  LabelImageType::Pointer    movingLabels, fixedLabels;
  std::string                organ;
  std::vector<bmr::Landmark> movingLandmarks, fixedLandmarks;
};

PairData
ReadPair(const itk::ImagePairEntry & pair, const CompareOptions & o, const std::string & dir, StageTimer & timer)
{
  PairData d;
  timer.Begin("read inputs");
  d.scene = bmr::ReadScene(pair.paths.at("scene"));
  d.movingCT = ReadImage<CTImageType>(pair.paths.at("moving_ct"), "moving CT");
  // A label input may be an RTSTRUCT, rasterized on the grid of the CT of the same scan.
  d.movingLabels = ReadLabelsOrRTStruct(pair.paths.at("moving_labels"), "moving label image", d.movingCT, d.scene);
  d.fixedCT = ReadImage<CTImageType>(pair.paths.at("fixed_ct"), "fixed CT");
  d.fixedLabels = ReadLabelsOrRTStruct(pair.paths.at("fixed_labels"), "fixed label image", d.fixedCT, d.scene);
  timer.End();
  const auto unknown = d.scene.UnknownLabels();
  d.organ = !o.seedOrgan.empty() ? o.seedOrgan : unknown.empty() ? std::string() : unknown.front()->name;
  const bmr::SceneLabel * organ = d.scene.FindLabel(d.organ);
  if (!organ)
  {
    throw std::runtime_error("pair \"" + pair.name + "\": no seed organ (give --seed-organ NAME of the scene)");
  }
  timer.Begin("landmarks");
  const std::string movingPath = pair.paths.count("moving_landmarks") ? pair.paths.at("moving_landmarks") : "";
  const std::string fixedPath = pair.paths.count("fixed_landmarks") ? pair.paths.at("fixed_landmarks") : "";
  if (!movingPath.empty() && !fixedPath.empty())
  {
    d.movingLandmarks = bmr::ReadLandmarks(movingPath);
    d.fixedLandmarks = bmr::ReadLandmarks(fixedPath);
  }
  else
  {
    itk::DetectPairedSeeds(d.movingCT,
                           d.movingLabels,
                           d.fixedCT,
                           d.fixedLabels,
                           organ->value,
                           "pair \"" + pair.name + "\"",
                           d.movingLandmarks,
                           d.fixedLandmarks);
    bmr::WriteLandmarks(dir + "/seeds_moving.csv", d.movingLandmarks);
    bmr::WriteLandmarks(dir + "/seeds_fixed.csv", d.fixedLandmarks);
  }
  timer.End(std::to_string(d.fixedLandmarks.size()) + " pairs");
  return d;
}

/** \a field placed exactly on \a fixed's grid when it has its size and its origin, spacing and direction agree to
 * 1e-4 of a voxel: other tools (plastimatch) write the geometry in single precision, which ITK's filters then
 * refuse as another physical space. Any other field is returned as it is. */
FieldType::Pointer
OnFixedGrid(FieldType::Pointer field, const LabelImageType * fixed)
{
  if (field->GetLargestPossibleRegion().GetSize() != fixed->GetLargestPossibleRegion().GetSize())
  {
    return field;
  }
  for (unsigned int i = 0; i < 3; ++i)
  {
    const double h = fixed->GetSpacing()[i];
    bool         close = std::abs(field->GetOrigin()[i] - fixed->GetOrigin()[i]) <= 1e-4 * h &&
                 std::abs(field->GetSpacing()[i] - h) <= 1e-4 * h;
    for (unsigned int j = 0; j < 3; ++j)
    {
      close = close && std::abs(field->GetDirection()(i, j) - fixed->GetDirection()(i, j)) <= 1e-4;
    }
    if (!close)
    {
      return field;
    }
  }
  field->CopyInformation(fixed);
  return field;
}

/** The fixed -> moving field of \a method on the pair, and its compute time [s] (-1 when given). */
FieldType::Pointer
MethodField(const std::string &         method,
            const itk::ImagePairEntry & pair,
            const PairData &            d,
            const CompareOptions &      o,
            const std::string &         dir,
            double &                    seconds)
{
  const std::string given = pair.paths.count(method + "_field") ? pair.paths.at(method + "_field") : "";
  seconds = 0.0;
  if (!given.empty())
  {
    seconds = -1.0;
    return OnFixedGrid(ReadImage<FieldType>(given, method + " field"), d.fixedLabels);
  }
  if (method == "identity")
  {
    auto field = FieldType::New();
    field->CopyInformation(d.fixedCT);
    field->SetRegions(d.fixedCT->GetLargestPossibleRegion());
    field->Allocate(true);
    return field;
  }
  if (method == "fem")
  {
    StageTimer fem(true);
    const auto result = itk::RegisterSegmentedPair(d.movingLabels, d.fixedLabels, d.movingCT, d.scene, o.fem, &fem);
    // Compute time only: writing compressed outputs is the same for every method and not part of it.
    for (const auto & s : result.state.stages)
    {
      seconds += s.seconds;
    }
    fem.stages = result.state.stages;
    WriteRegistration(dir + "/fem", result, o.fem, itk::RegistrationOutputs(), fem);
    return result.state.pullBack;
  }
  const std::string flatten = o.flatten.empty() ? d.organ : o.flatten;
  std::cout << "  Demons (" << o.demons.variant << ", " << o.demons.levels << " levels x " << o.demons.iterations
            << " iterations, flattened labels: " << flatten << ") ..." << std::flush;
  const auto start = Clock::now();
  auto       field = itk::RunDemonsBaseline(
    d.fixedCT, d.movingCT, d.fixedLabels, d.movingLabels, bmr::ParseLabelList(flatten, &d.scene), o.demons);
  seconds = std::chrono::duration<double>(Clock::now() - start).count();
  std::cout << " " << std::fixed << std::setprecision(1) << seconds << " s" << std::endl;
  MakeOutputDirectory(dir + "/demons");
  itk::WriteImageAtomically(field.GetPointer(), dir + "/demons/field.nrrd");
  return field;
}

/** Every method on one pair: fields, scores, checkerboards, table rows. */
void
ComparePair(const itk::ImagePairEntry & pair,
            const CompareOptions &      o,
            const std::string &         out,
            itk::ComparisonTables &     tables)
{
  std::cout << "\n=== pair " << pair.name << " ===" << std::endl;
  const std::string dir = out + "/" + pair.name;
  MakeOutputDirectory(dir);
  StageTimer     timer;
  const PairData d = ReadPair(pair, o, dir, timer);
  // Center of the checkerboard slice: the seeds' centroid in the fixed image.
  itk::Point<double, 3> center;
  center.Fill(0.0);
  for (const auto & l : d.fixedLandmarks)
  {
    for (int a = 0; a < 3; ++a)
    {
      center[a] += l.point[a] / double(d.fixedLandmarks.size());
    }
  }
  for (const std::string & method : o.methods)
  {
    double     seconds = 0.0;
    const auto field = MethodField(method, pair, d, o, dir, seconds);
    const auto evaluation =
      itk::EvaluateField(field, d.movingLabels, d.fixedLabels, d.scene, d.movingLandmarks, d.fixedLandmarks);
    const auto warpedCT = itk::WarpImage(d.movingCT.GetPointer(), field.GetPointer(), false, -1000.0f);
    itk::WriteCheckerboardPNG(d.fixedCT, warpedCT, center, dir + "/checkerboard_" + method + ".png");
    tables.Add(pair.name, method, seconds, d.fixedLandmarks, evaluation);
    std::cout << "  " << std::left << std::setw(9) << method << std::right << " "
              << itk::ComparisonTables::Summary(evaluation, seconds) << std::endl;
  }
}
} // namespace

int
CompareCommand(const Arguments & args)
{
  const std::string    listPath = args.Require("--pairs");
  const std::string    out = args.Require("--out");
  const CompareOptions o = ParseCompareOptions(args);
  args.CheckAllUsed();
  // Every input is checked before anything is written: a bad list leaves no partial output.
  const std::vector<itk::ImagePairEntry> pairs = itk::ReadImagePairList(listPath);
  for (const auto & pair : pairs)
  {
    for (const auto & kv : pair.paths)
    {
      if (!kv.second.empty() && !std::filesystem::exists(kv.second))
      {
        throw std::runtime_error("pair \"" + pair.name + "\": " + kv.first + " \"" + kv.second + "\" does not exist");
      }
    }
    bmr::ReadScene(pair.paths.at("scene"));
  }
  MakeOutputDirectory(out);
  itk::ComparisonTables tables(o.tag);
  for (const auto & pair : pairs)
  {
    ComparePair(pair, o, out, tables);
  }
  bmr::WriteTextFileAtomically(out + "/per_landmark.csv", tables.PerLandmarkCsv());
  bmr::WriteTextFileAtomically(out + "/per_pair.csv", tables.PerPairCsv());
  bmr::WriteTextFileAtomically(out + "/per_organ.csv", tables.PerOrganCsv());
  bmr::WriteTextFileAtomically(out + "/ttests.csv", tables.TTestsCsv());
  bmr::WriteTextFileAtomically(out + "/summary.md", tables.SummaryMarkdown());
  std::cout << "\n"
            << tables.SummaryMarkdown() << "\nWrote " << out
            << "/{summary.md, per_pair.csv, per_organ.csv, per_landmark.csv, ttests.csv, <pair>/checkerboard_*.png}"
            << "\n(plots: /usr/bin/python3 scripts/plot_compare.py " << out << ")" << std::endl;
  return EXIT_SUCCESS;
}

namespace {
/** Option \a key as LOW,HIGH within [\a min, \a max] with LOW <= HIGH, or \a fallback when absent. */
std::array<double, 2>
Range(const Arguments & args, const std::string & key, const std::array<double, 2> & fallback, double min, double max)
{
  if (!args.Has(key))
  {
    return fallback;
  }
  const std::string     text = args.Get(key);
  std::array<double, 2> range{ { 0.0, 0.0 } };
  char *                end = nullptr;
  range[0] = std::strtod(text.c_str(), &end);
  const bool comma = *end == ',';
  range[1] = comma ? std::strtod(end + 1, &end) : 0.0;
  if (!comma || *end != '\0' || !(range[0] >= min && range[0] <= range[1] && range[1] <= max))
  {
    std::ostringstream os;
    os << key << " expects LOW,HIGH with " << min << " <= LOW <= HIGH <= " << max << ", got \"" << text << "\"";
    throw UsageError(os.str());
  }
  return range;
}
} // namespace

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
  itk::PhantomSetRanges ranges;
  ranges.prostateE = Range(args, "--prostate-E-range", ranges.prostateE, 1.0, 10000.0);
  ranges.bladderMM = Range(args, "--bladder-range", ranges.bladderMM, 0.01, 40.0);
  ranges.rectumMM = Range(args, "--rectum-range", ranges.rectumMM, 0.01, 40.0);
  args.CheckAllUsed();
  MakeOutputDirectory(out);
  std::ostringstream list, parameters;
  list << "# pelvis phantom pairs with ground-truth seed landmarks (biomechreg phantom-set)\n"
       << "name,moving_ct,moving_labels,fixed_ct,fixed_labels,scene,moving_landmarks,fixed_landmarks\n";
  parameters << "name,true_E_kPa,bladder_mm,rectum_mm,seed\n";
  const auto set = itk::DrawPhantomSet(static_cast<unsigned int>(count), static_cast<std::uint64_t>(seed), ranges);
  for (std::size_t k = 0; k < set.size(); ++k)
  {
    const itk::PhantomSettings & o = set[k];
    const std::string            name = "pair" + std::to_string(k + 1);
    std::cout << "\n"
              << name << ": prostate " << o.prostateE << " kPa, bladder +" << o.bladderMM << " mm, rectum +"
              << o.rectumMM << " mm, seed " << o.seed << std::endl;
    StageTimer timer;
    WritePhantom(out + "/" + name, itk::MakePhantomPair(o, &timer), o, timer);
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
