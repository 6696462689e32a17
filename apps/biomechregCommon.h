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
// Shared pieces of the biomechreg command-line tool: argument parsing, the stage printer, image I/O and
// the writers of the pipelines' results. The work itself is done by the library (itkBiomechanicalPipelines.h).
#ifndef biomechregCommon_h
#define biomechregCommon_h

#include "bmrAtomicFile.h"
#include "itkBiomechanicalImageIO.h"
#include "itkBiomechanicalPipelines.h"
#include "itkBiomechanicalWriters.h"
#include "itkImageWarper.h"

#include <chrono>
#include <iomanip>
#include <iostream>
#include <map>
#include <set>
#include <sstream>

namespace bmrcli {
using CTImageType = itk::BiomechanicalCTImageType;
using LabelImageType = itk::BiomechanicalLabelImageType;
using FieldType = itk::BiomechanicalFieldType;
using Clock = std::chrono::steady_clock;
using Stages = std::vector<itk::PipelineStage>;

struct UsageError : std::runtime_error
{
  using std::runtime_error::runtime_error;
};

// ---------------------------------------------------------------- console manners (biomechregConsole.cxx)

enum class Verbosity
{
  Quiet,  ///< warnings (on stderr) and errors only
  Normal, ///< the stages, their times and the results
  Verbose ///< also one line per inner solve of the estimation and ITK's debug output
};

/** The options every subcommand takes; main() takes them out before the subcommand parses its own. */
struct GlobalOptions
{
  bool         help{ false };
  bool         version{ false };
  bool         quiet{ false };
  bool         verbose{ false };
  unsigned int threads{ 0 }; ///< the library's and ITK's threads (the BLAS runs on one); 0: all cores
  std::string  taskTrace;    ///< where to write the parallel work's trace (bmr::TaskTrace); empty: none
};

/** Which malloc the program runs on, and whether it asked for transparent huge pages (biomechregMalloc.cxx). */
std::string
MallocDescription();

/** From now on the stages are also reported in 3D Slicer's progress tags (<filter-start>, <filter-progress>,
 * <filter-end>) on stdout, each on a line of its own: biomechreg runs as a Slicer module (biomechregSlicer.h). */
void
UseSlicerProgress();
/** Whether UseSlicerProgress() was called. */
bool
SlicerProgress();

/** Removes --help/-h, --version, --quiet/-q, --verbose/-v, --threads N and --task-trace FILE from \a args. */
GlobalOptions
TakeGlobalOptions(std::vector<std::string> & args);
/** Verbosity, thread counts, and ITK's output window (warnings as one "warning: ..." line). */
void
ApplyGlobalOptions(const GlobalOptions & options);
Verbosity
GetVerbosity();
/** \a text on a line of its own (stdout, or stderr for a \a warning under --quiet), also while a stage line is
 * open: that line is ended and printed again after it. */
void
PrintLine(const std::string & text, bool warning = false);
/** "warning: <message>" on a line of its own (stdout; stderr under --quiet), even while a stage line is open. */
void
PrintWarning(const std::string & message);
/** ITK's "WARNING: In FILE, line N\nClass (0x...): text" reduced to "text", on one line. */
std::string
StripITKPrefix(const std::string & text);
/** A stage's line is opened when it begins and closed with its time; a progress bar may redraw it meanwhile. */
void
OpenStageLine(const std::string & text);
void
CloseStageLine(const std::string & rest);
/** Ends an open stage line with "failed" (nothing when none is open); called before an error is printed. */
void
EndStageLineOnError();
/** On a terminal, redraws the open stage line with a bar (\a fraction in [0, 1]; negative: unknown), the
 * elapsed and the remaining time; otherwise does nothing. */
void
ShowProgress(double fraction, double elapsedSeconds, const std::string & detail);
bool
IsTerminal();
/** The process's peak resident memory so far [MB]. */
double
PeakMemoryMB();
/** The usage of \a command, or of every command when it is empty. */
void
PrintUsage(std::ostream & os, const std::string & command = std::string());
bool
IsCommand(const std::string & command);

/** Prints the stages of a run as they happen (its own and the library's), its warnings and, with
 * \c iterations, one line per inner solve of the estimation; collects its own stages. */
class StageTimer : public itk::PipelineObserver
{
public:
  /** \a iterations: print the inner solves (under --verbose). */
  explicit StageTimer(bool iterations = false)
    : m_Iterations(iterations && GetVerbosity() == Verbosity::Verbose)
  {}
  void
  StageBegin(const std::string & name) override;
  void
  StageEnd(const std::string & name, double seconds, const std::string & detail) override;
  void
  Warning(const std::string & message) override;
  void
  Iteration(const bmr::IterationRecord & record) override;
  void
  Progress(double fraction, const std::string & detail) override;
  /** A stage of the command itself, recorded in \c stages. */
  void
  Begin(const std::string & name);
  void
  End(const std::string & detail = std::string());

  Stages stages;

private:
  bool              m_Iterations;
  unsigned int      m_Solves{ 0 }; ///< inner solves of the running stage (for the progress line)
  Clock::time_point m_StageStart;  ///< of the stage that StageBegin() opened (the library's or our own)
  Clock::time_point m_Start;
  std::string       m_Current;
};

/** The table of stage wall times, their total and the peak memory. */
void
PrintTimings(const Stages & stages);

using itk::MakeOutputDirectory;

template<typename TImage>
typename TImage::Pointer
ReadImage(const std::string & path, const std::string & what)
{
  return itk::ReadBiomechanicalImage<TImage>(path, what);
}

/** A label map from \a path: a DICOM RTSTRUCT (a file whose Modality is RTSTRUCT) rasterized onto \a ctGrid (the
 * CT of the same scan) by itk::ReadRTStructAsLabelImage(), its ROI names mapped to the names of \a scene's labels
 * other than the outside ones (case-insensitively; every one must be in the file, and every ROI of the file
 * must be one of them; voxels outside every ROI get the scene's first outside label, or 0); any other path is
 * read as a label image (ReadImage). \a ignoreUnmappedROIs: ROIs that are no scene label (BODY, couch, PTV) are
 * skipped instead of refused. Errors name \a what and the file. */
LabelImageType::Pointer
ReadLabelsOrRTStruct(const std::string &       path,
                     const std::string &       what,
                     const itk::ImageBase<3> * ctGrid,
                     const bmr::Scene &        scene,
                     bool                      ignoreUnmappedROIs = false);

class Arguments;
/** register's label inputs, its scene (empty: the built-in pelvis scene of two structure sets), --roi-map and --out. */
struct RegistrationPaths
{
  std::string movingLabels, fixedLabels, scene, roiMap, out;
  std::string movingLabelNames, fixedLabelNames; ///< names tables of label maps (built-in scene only)
};

/** The scene and label maps register works on; with structure sets, the fixed ROI of each objective organ. */
struct RegistrationAnatomy
{
  bmr::Scene                         scene;
  LabelImageType::Pointer            movingLabels, fixedLabels;
  std::map<std::string, std::string> fixedROIOfOrgan;
};

/** With a scene: it and the label maps (or RTSTRUCTs named as its labels, ReadLabelsOrRTStruct()). Without: both
 * label inputs must be RTSTRUCTs, read with the built-in pelvis scene (itk::ReadClinicalPelvisAnatomy(), --roi-map
 * overrides), the mapping printed and written to structure_set.json, the label maps to *_labels_from_rois.nrrd
 * (biomechregStructureSet.cxx). */
RegistrationAnatomy
ReadRegistrationAnatomy(const RegistrationPaths & paths,
                        const CTImageType *       movingCT,
                        const CTImageType *       fixedCT,
                        bool                      ignoreROIs);

/** --unmapped-rois ignore|refuse (default refuse): what ReadLabelsOrRTStruct() does with ROIs of an RTSTRUCT that
 * are no scene label. */
bool
IgnoreUnmappedROIs(const Arguments & args);

// ------------------------------------------------------------ argument parsing

/** The rarely needed settings of register's interval, given together as --uncertainty-options NAME=VALUE,... (each
 * also as its own option --uncertainty-NAME VALUE). */
constexpr const char * AdvancedUncertaintyOptions[] = { "mesh-jitter",     "shift-voxels",     "rotation-deg",
                                                        "wall-slip",       "smoothing-voxels", "simulation-mesh-scale",
                                                        "bias-correction", "warm-start",       "step-tolerance",
                                                        "quantiles",       "voxel-limit-mm" };

class Arguments
{
public:
  /** The options of \a args as --NAME VALUE pairs; --uncertainty-options NAME=VALUE,... is read as the options
   * --uncertainty-NAME VALUE (NAME one of AdvancedUncertaintyOptions; an option given both ways is an error). */
  explicit Arguments(const std::vector<std::string> & args);
  bool
  Has(const std::string & key) const
  {
    return m_Values.count(key) > 0;
  }
  std::string
  Get(const std::string & key, const std::string & fallback = std::string()) const;
  std::string
  Require(const std::string & key) const;
  double
  Number(const std::string & key, double fallback) const;
  /** An integer in [lo, hi]. */
  unsigned int
  Count(const std::string & key, unsigned int fallback, unsigned int lo, unsigned int hi) const;
  std::array<double, 3>
  Triple(const std::string & key, const std::array<double, 3> & fallback) const;
  /** A required comma-separated list (empty items refused). */
  std::vector<std::string>
  RequireList(const std::string & key) const;
  /** NAME=NUMBER,... (finite numbers; empty when the option is absent). */
  std::map<std::string, double>
  NamedNumbers(const std::string & key) const;
  /** One of \a choices. */
  std::string
  Choice(const std::string & key, const std::vector<std::string> & choices) const;
  void
  CheckAllUsed() const;

private:
  void
  ExpandUncertaintyOptions();

  std::map<std::string, std::string> m_Values;
  mutable std::set<std::string>      m_Used;
};

// ---------------------------------------------------------------- register

/** Reads register's settings (--sweep-samples, --coarse-factor, --mesh-scale, --wall-*, --max-outer-iterations,
 * --outer-tolerance, --element-inversion; register, compare); defaults from itk::RegistrationSettings. */
itk::RegistrationSettings
ParseRegistrationSettings(const Arguments & args);

/** --outputs LIST, --field-precision float|double, --compression-level N (register, demo). */
itk::RegistrationOutputs
ParseRegistrationOutputs(const Arguments & args);

/** Writes the registration's \a outputs into \a out (report.json's wall times: the timer's stages, which end
 * with the writing). */
void
WriteRegistration(const std::string &               out,
                  const itk::RegistrationResult &   result,
                  const itk::RegistrationSettings & settings,
                  const itk::RegistrationOutputs &  outputs,
                  StageTimer &                      timer);

/** The accepted outer iterates (E, Phi*) and the outer stop condition. */
void
PrintOuterIterations(const itk::RegistrationResult & result);

int
RegisterCommand(const Arguments & args);

// ---------------------------------------------------------------- phantom

/** The phantom grid from --size, --spacing [mm], --origin [mm] and --rotate-z-deg (phantom, phantom-cohort). */
bmr::GridGeometry
GridFromArguments(const Arguments & args, const bmr::GridGeometry & defaults);

/** Writes a phantom pair into \a out: the four images, truth_field.nrrd, scene.json, truth_scene.json,
 * truth.json and the landmark files. */
void
WritePhantom(const std::string &          out,
             const itk::PhantomPair &     pair,
             const itk::PhantomSettings & settings,
             StageTimer &                 timer);

// ---------------------------------------------------------------- Demons and compare

/** Reads --demons-variant, --demons-levels, --demons-iterations, --demons-sigma, --histogram-matching. */
itk::DemonsSettings
ParseDemonsSettings(const Arguments & args);

int
DemonsCommand(const Arguments & args);
/** biomechreg warp (biomechregWarp.cxx). */
int
WarpCommand(const Arguments & args);
int
CompareCommand(const Arguments & args);
int
PhantomSetCommand(const Arguments & args);

// ---------------------------------------------------------------- cohorts

int
PhantomCohortCommand(const Arguments & args);
int
CohortCommand(const Arguments & args, const std::string & executable);
int
CohortStatsCommand(const Arguments & args);

} // namespace bmrcli

#endif
