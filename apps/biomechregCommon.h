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
#include "bmrVtuWriter.h"
#include "itkBiomechanicalImageIO.h"
#include "itkBiomechanicalPipelines.h"
#include "itkImageWarper.h"

#include <chrono>
#include <filesystem>
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

/** Prints the stages of a run as they happen (its own and the library's), its warnings and, with
 * \c iterations, one line per inner solve of the estimation; collects its own stages. */
class StageTimer : public itk::PipelineObserver
{
public:
  explicit StageTimer(bool iterations = false)
    : m_Iterations(iterations)
  {}
  void
  StageBegin(const std::string & name) override;
  void
  StageEnd(const std::string & name, double seconds, const std::string & detail) override;
  void
  Warning(const std::string & message) override;
  void
  Iteration(const bmr::IterationRecord & record) override;
  /** A stage of the command itself, recorded in \c stages. */
  void
  Begin(const std::string & name);
  void
  End(const std::string & detail = std::string());

  Stages stages;

private:
  bool              m_Iterations;
  Clock::time_point m_Start;
  std::string       m_Current;
};

/** The table of stage wall times and their total. */
void
PrintTimings(const Stages & stages);

/** Like mkdir -p. */
inline void
MakeDirectory(const std::string & path)
{
  std::error_code error;
  std::filesystem::create_directories(path, error);
  if (error || !std::filesystem::is_directory(path))
  {
    throw std::runtime_error("cannot create output directory \"" + path + "\"");
  }
}

template<typename TImage>
typename TImage::Pointer
ReadImage(const std::string & path, const std::string & what)
{
  return itk::ReadBiomechanicalImage<TImage>(path, what);
}

template<typename TImage>
void
WriteImage(const TImage * image, const std::string & path)
{
  itk::WriteImageAtomically(image, path);
}

/** mesh.vtu: displacement [mm], force [mN], Dirichlet flags; label, E [kPa], nu, von Mises [kPa]. */
void
WriteMesh(const std::string & path, const itk::SimulationResult & s);

/** Writes mesh.vtu, field.nrrd, forward_field.nrrd (when computed) and the warped images into \a out. */
void
WriteSimulationOutputs(const std::string &           out,
                       const itk::SimulationResult & s,
                       const LabelImageType *        warpedLabels,
                       const CTImageType *           warpedCT);

// ------------------------------------------------------------ argument parsing

class Arguments
{
public:
  Arguments(int argc, char * argv[], int first);
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
  /** One of \a choices. */
  std::string
  Choice(const std::string & key, const std::vector<std::string> & choices) const;
  void
  CheckAllUsed() const;

private:
  std::map<std::string, std::string> m_Values;
  mutable std::set<std::string>      m_Used;
};

// ---------------------------------------------------------------- register

/** The modulus with " (uncertainty x/ exp(s), i.e. +-N %, one standard deviation)" when computed. */
std::string
UncertaintyText(const itk::RegistrationResult & result, const std::string & label);

/** Reads register's settings (--sweep-samples, --coarse-factor, --mesh-scale, --wall-*, --max-outer-iterations,
 * --outer-tolerance, --element-inversion; register, compare); defaults from itk::RegistrationSettings. */
itk::RegistrationSettings
ParseRegistrationSettings(const Arguments & args);

/** Writes a registration's outputs into \a out: field, forward field, warped images, mesh.vtu,
 * history.csv, sweep.csv and report.json (wall times: the timer's stages, which end with the writing). */
void
WriteRegistration(const std::string &               out,
                  const itk::RegistrationResult &   result,
                  const itk::RegistrationSettings & settings,
                  StageTimer &                      timer);

/** The accepted outer iterates (E, Phi*) and the outer stop condition. */
void
PrintOuterIterations(const itk::RegistrationResult & result);

int
RegisterCommand(const Arguments & args);

// ---------------------------------------------------------------- phantom

/** Writes a phantom pair into \a out: the four images, truth_field.nrrd, scene.json, truth_scene.json,
 * truth.json and the landmark files. */
void
WritePhantom(const std::string &          out,
             const itk::PhantomPair &     pair,
             const itk::PhantomSettings & settings,
             StageTimer &                 timer);

// ---------------------------------------------------------------- Demons and compare

/** Settings of the Demons baseline (itk::DemonsBaselineRegistrationFilter; defaults as documented there). */
struct DemonsSettings
{
  std::string  variant{ "diffeomorphic" }; ///< or "symmetric" (fast symmetric forces)
  unsigned int levels{ 3 };
  unsigned int iterations{ 50 }; ///< per level
  double       sigma{ 1.5 };     ///< field smoothing [voxels]
  bool         histogramMatching{ true };
};

/** Reads --demons-variant, --demons-levels, --demons-iterations, --demons-sigma, --histogram-matching. */
DemonsSettings
ParseDemonsSettings(const Arguments & args);

/** Demons of the moving CT onto the fixed CT; returns the fixed -> moving field [mm]. The labels are
 * used only when \a flatten names organs to flatten. */
FieldType::Pointer
RunDemons(const CTImageType *               fixedCT,
          const CTImageType *               movingCT,
          const LabelImageType *            fixedLabels,
          const LabelImageType *            movingLabels,
          const std::vector<std::int32_t> & flatten,
          const DemonsSettings &            settings);

/** Comma-separated labels, by value or (with a scene) by name; "none" gives an empty list. */
std::vector<std::int32_t>
ParseLabelList(const std::string & text, const bmr::Scene * scene);

int
DemonsCommand(const Arguments & args);
int
CompareCommand(const Arguments & args);
int
PhantomSetCommand(const Arguments & args);

} // namespace bmrcli

#endif
