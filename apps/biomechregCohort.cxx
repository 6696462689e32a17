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
// biomechreg phantom-cohort: a synthetic cohort with its truth (patients with their own anatomy, stage and modulus).
// biomechreg cohort: the cohort workflow on Snakemake (one registration per daily image, then the statistics).
// biomechreg cohort-stats: the statistics of a cohort's registrations (the workflow's last step).
#include "biomechregCommon.h"
#include "bmrCohortStudy.h"
#include "itkBiomechanicalReports.h"
#include "itkPhantomCohort.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <thread>

namespace bmrcli {
namespace {

// ------------------------------------------------------------- phantom-cohort

itk::PhantomCohortSettings
ParsePhantomCohortSettings(const Arguments & args)
{
  itk::PhantomCohortSettings s;
  s.patients = args.Count("--patients", s.patients, 1, 999);
  s.fractions = args.Count("--fractions", s.fractions, 1, 99);
  s.seed = args.Count("--seed", 1, 0, 1000000);
  s.base = itk::PhantomSettings::Defaults(itk::PhantomSettings::AnatomyEnum::Pelvis);
  s.base.grid = GridFromArguments(args, s.base.grid);
  s.base.noiseHU = args.Number("--noise-HU", s.base.noiseHU);
  s.base.truthRefinement = args.Number("--truth-mesh-scale", s.base.truthRefinement);
  if (!(s.base.truthRefinement >= 0.3 && s.base.truthRefinement <= 2.0) || !(s.base.noiseHU >= 0.0))
  {
    throw UsageError("--truth-mesh-scale must lie in [0.3, 2] and --noise-HU be >= 0");
  }
  s.base.fixedGridShiftVoxels = args.Number("--fixed-grid-shift-voxels", 0.5);
  if (!(s.base.fixedGridShiftVoxels >= 0.0 && s.base.fixedGridShiftVoxels <= 0.5))
  {
    throw UsageError("--fixed-grid-shift-voxels must lie in [0, 0.5]");
  }
  s.base.model = args.Choice("--model", { "linear", "neo_hookean" }) == "neo_hookean"
                   ? bmr::MaterialModelEnum::NeoHookean
                   : bmr::MaterialModelEnum::Linear;
  return s;
}

} // namespace

int
PhantomCohortCommand(const Arguments & args)
{
  const std::string out = args.Require("--out");
  const auto        settings = ParsePhantomCohortSettings(args);
  args.CheckAllUsed();
  const auto cohort = itk::DrawPhantomCohort(settings);
  for (const auto & patient : cohort)
  {
    std::cout << patient.name << ": T" << patient.stage << ", prostate " << patient.prostateE << " kPa, scale "
              << patient.anatomy.prostateScale << std::endl;
  }
  StageTimer timer;
  itk::WritePhantomCohort(out, cohort, &timer);
  for (const auto & t : itk::PhantomCohortTruthCorrelations(cohort))
  {
    std::cout << "  truth: " << bmr::ToString(t.method) << " " << t.coefficient << " (p " << t.pValueApproximate << ")"
              << std::endl;
  }
  std::cout << "Wrote " << out << "/cohort.csv (for biomechreg cohort --cohort) and truth*.csv" << std::endl;
  return EXIT_SUCCESS;
}

// --------------------------------------------------------------------- cohort

namespace {

/** The shipped workflow: $BMR_WORKFLOWS/cohort/Snakefile, else next to the executable
 * (<prefix>/share/biomechreg/workflows, as installed), else in the source tree this binary was built from. */
std::string
FindCohortSnakefile(const std::string & executable)
{
  namespace fs = std::filesystem;
  std::vector<fs::path> candidates;
  if (const char * root = std::getenv("BMR_WORKFLOWS"))
  {
    candidates.push_back(fs::path(root) / "cohort" / "Snakefile");
  }
  candidates.push_back(fs::path(executable).parent_path().parent_path() / "share" / "biomechreg" / "workflows" /
                       "cohort" / "Snakefile");
  candidates.push_back(fs::path(BMR_SOURCE_DIR) / "workflows" / "cohort" / "Snakefile");
  for (const auto & c : candidates)
  {
    std::error_code error;
    if (fs::is_regular_file(c, error))
    {
      return c.string();
    }
  }
  throw std::runtime_error("the cohort workflow (workflows/cohort/Snakefile) is not installed; set BMR_WORKFLOWS to "
                           "the folder that holds cohort/Snakefile");
}

std::string
ShellQuoted(const std::string & s)
{
  std::string q = "'";
  for (char c : s)
  {
    q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  }
  return q + "'";
}

std::vector<std::string>
SplitOptions(const std::string & text)
{
  std::istringstream       in(text);
  std::vector<std::string> options;
  for (std::string o; in >> o;)
  {
    options.push_back(o);
  }
  if (std::find(options.begin(), options.end(), "--outputs") == options.end())
  {
    // A cohort needs the report only; the fields of 60 pairs would take gigabytes.
    options.insert(options.begin(), { "--outputs", "report" });
  }
  return options;
}

/** Holds an exclusive lock on the study directory while this process lives (the kernel releases it when the
 * process ends, killed or not), so two runs never write one study. Snakemake's own lock is not used: a killed
 * run leaves it behind. */
class StudyLock
{
public:
  explicit StudyLock(const std::string & directory)
    : m_File(::open((directory + "/.biomechreg-cohort.lock").c_str(), O_CREAT | O_RDWR | O_CLOEXEC, 0644))
  {
    if (m_File < 0 || ::flock(m_File, LOCK_EX | LOCK_NB) != 0)
    {
      throw std::runtime_error("the study directory \"" + directory + "\" is in use by another biomechreg cohort");
    }
  }
  ~StudyLock() { ::close(m_File); }
  StudyLock(const StudyLock &) = delete;
  StudyLock &
  operator=(const StudyLock &) = delete;

private:
  int m_File;
};

/** Writes the study's CSVs and report; returns it. */
bmr::CohortStudy
WriteCohortStatistics(const bmr::Cohort & cohort, const std::string & study)
{
  const bmr::CohortStudy s = bmr::CohortStudy::Summarize(cohort, study);
  bmr::WriteTextFileAtomically(study + "/cohort_fractions.csv", s.FractionsCsv());
  bmr::WriteTextFileAtomically(study + "/cohort_patients.csv", s.PatientsCsv());
  bmr::WriteTextFileAtomically(study + "/cohort_correlations.csv", s.CorrelationsCsv());
  bmr::WriteTextFileAtomically(study + "/cohort_report.md", s.ReportMarkdown());
  return s;
}

void
PrintCorrelations(const bmr::CohortStudy & s)
{
  for (const auto & c : s.correlations)
  {
    if (c.tests.empty())
    {
      std::cout << "  " << c.material << " / " << c.covariate << ": " << c.note << std::endl;
    }
    for (const auto & t : c.tests)
    {
      std::cout << "  " << c.material << " / " << c.covariate << ": " << bmr::ToString(t.method) << " " << std::fixed
                << std::setprecision(3) << t.coefficient << " (p " << std::setprecision(4) << t.pValueApproximate
                << (t.permutationExact ? ", exact permutation p " : "")
                << (t.permutationExact ? std::to_string(t.pValuePermutation) : "") << ", n " << t.count << ")"
                << std::endl;
    }
  }
}

} // namespace

int
CohortCommand(const Arguments & args, const std::string & executable)
{
  const std::string           cohortPath = args.Require("--cohort");
  const std::string           out = args.Require("--out");
  bmr::CohortWorkflowSettings settings;
  const unsigned int cores = args.Count("--cores", std::max(1u, std::thread::hardware_concurrency()), 1, 100000);
  settings.threadsPerJob = args.Count("--threads-per-job", 1, 1, 1024);
  settings.memoryMB = args.Count("--mem-mb", settings.memoryMB, 100, 10000000);
  settings.runtimeMinutes = args.Count("--runtime-min", settings.runtimeMinutes, 1, 100000);
  settings.registerOptions = SplitOptions(args.Get("--register-options"));
  const std::string profile = args.Get("--profile");
  const bool        dryRun = args.Choice("--dry-run", { "off", "on" }) == "on";
  args.CheckAllUsed();

  const bmr::Cohort cohort = bmr::Cohort::Read(cohortPath); // every row checked before a job starts
  settings.executable = executable;
  const std::string snakefile = FindCohortSnakefile(executable);
  itk::MakeOutputDirectory(out);
  const StudyLock lock(out);
  bmr::WriteTextFileAtomically(out + "/workflow.json", bmr::CohortWorkflowConfigJson(cohort, settings));
  std::cout << "biomechreg cohort: " << cohort.patients.size() << " patients, " << cohort.fractions.size()
            << " fractions -> " << out << " (Snakemake, " << cores << " cores)" << std::endl;
  std::string command = "snakemake --snakefile " + ShellQuoted(snakefile) + " --directory " + ShellQuoted(out) +
                        " --configfile " + ShellQuoted(out + "/workflow.json") + " --cores " + std::to_string(cores) +
                        " --keep-going --rerun-incomplete --nolock";
  command += profile.empty() ? std::string() : " --profile " + ShellQuoted(profile);
  command += dryRun ? " --dry-run" : "";
  const int status = std::system(command.c_str());
  if (dryRun)
  {
    return status == 0 ? EXIT_SUCCESS : EXIT_FAILURE;
  }
  if (status != 0)
  {
    // Some jobs failed (or Snakemake did): the statistics of what is there, the missing ones named with their logs.
    const bmr::CohortStudy s = WriteCohortStatistics(cohort, out);
    PrintCorrelations(s);
    std::cerr << "biomechreg: error: " << s.NumberOfMissingFractions() << " of " << s.fractions.size()
              << " fractions have no result (their logs are listed in " << out
              << "/cohort_report.md); run the same command again to retry only those" << std::endl;
    return EXIT_FAILURE;
  }
  std::cout << "Wrote " << out << "/cohort_report.md, cohort_{patients,fractions,correlations}.csv, cohort_*.png"
            << std::endl;
  return EXIT_SUCCESS;
}

int
CohortStatsCommand(const Arguments & args)
{
  const std::string cohortPath = args.Require("--cohort");
  const std::string study = args.Require("--study");
  args.CheckAllUsed();
  const bmr::CohortStudy s = WriteCohortStatistics(bmr::Cohort::Read(cohortPath), study);
  std::cout << "biomechreg cohort-stats: " << s.fractions.size() - s.NumberOfMissingFractions() << " of "
            << s.fractions.size() << " fractions registered" << std::endl;
  PrintCorrelations(s);
  if (s.NumberOfMissingFractions() > 0)
  {
    std::cout << "warning: " << s.NumberOfMissingFractions() << " fractions are missing (see cohort_report.md)"
              << std::endl;
  }
  return EXIT_SUCCESS;
}

} // namespace bmrcli
