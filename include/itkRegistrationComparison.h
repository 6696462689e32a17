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
#ifndef itkRegistrationComparison_h
#define itkRegistrationComparison_h

#include "bmrLandmarks.h"
#include "bmrScene.h"
#include "itkBiomechanicalPipelines.h"
#include "itkRegistrationQualityMeasures.h"

#include <map>
#include <string>
#include <vector>

namespace itk {

/** One line of a pair list: a name and its files (column -> path, relative paths resolved against the
 * list's directory, "" when absent). \ingroup BiomechanicalRegistration BiomechanicalRegistrationEvaluation */
struct BiomechanicalRegistration_EXPORT ImagePairEntry
{
  std::string                        name;
  std::map<std::string, std::string> paths;
};

/** Reads a pair list (CSV, '#' comments): required columns name, moving_ct, moving_labels, fixed_ct,
 * fixed_labels, scene; optional moving_landmarks, fixed_landmarks, fem_field, demons_field. Throws naming
 * the file, line and column on an unknown or missing column, a wrong field count, an empty required path,
 * a bad or repeated name, or an empty list. */
BiomechanicalRegistration_EXPORT std::vector<ImagePairEntry>
                                 ReadImagePairList(const std::string & path);

/** How one fixed -> moving field scores on a pair: TRE [mm] per landmark (in the fixed landmarks' order),
 * overlap and symmetric surface distances [mm] of the scene's objective organs after warping the moving
 * labels, and the field's Jacobian determinant. \ingroup BiomechanicalRegistration BiomechanicalRegistrationEvaluation
 */
struct BiomechanicalRegistration_EXPORT FieldEvaluation
{
  std::vector<double>                              tre;
  std::map<std::string, LabelOverlap>              overlap;
  std::map<std::string, SurfaceDistanceStatistics> surface;
  JacobianDeterminantStatistics                    jacobian;
};

BiomechanicalRegistration_EXPORT FieldEvaluation
EvaluateField(const BiomechanicalFieldType *      field,
              const BiomechanicalLabelImageType * movingLabels,
              const BiomechanicalLabelImageType * fixedLabels,
              const bmr::Scene &                  scene,
              const std::vector<bmr::Landmark> &  movingLandmarks,
              const std::vector<bmr::Landmark> &  fixedLandmarks);

/** Implanted seeds detected in both CTs inside \a organ and paired (itk::DetectImplantedSeeds,
 * bmr::MatchLandmarks): fixed[i] is the partner of moving[i] and has its id. Throws, naming \a what, when
 * the counts differ or no seed is found. */
BiomechanicalRegistration_EXPORT void
DetectPairedSeeds(const BiomechanicalCTImageType *    movingCT,
                  const BiomechanicalLabelImageType * movingLabels,
                  const BiomechanicalCTImageType *    fixedCT,
                  const BiomechanicalLabelImageType * fixedLabels,
                  std::int32_t                        organ,
                  const std::string &                 what,
                  std::vector<bmr::Landmark> &        moving,
                  std::vector<bmr::Landmark> &        fixed);

/** A 4 x 4 checkerboard of \a fixed and \a warped on the axial slice through \a center (soft-tissue window
 * -200 ... 300 HU) as a PNG, as dissertation Fig. 3.12. */
BiomechanicalRegistration_EXPORT void
WriteCheckerboardPNG(const BiomechanicalCTImageType * fixed,
                     const BiomechanicalCTImageType * warped,
                     const Point<double, 3> &         center,
                     const std::string &              path);

/** \brief The tables of a comparison of registration methods on seed landmarks (dissertation Table 3.5).
 *
 * Add() one row per pair and method; the tables are CSV (per landmark, per pair, per organ, t-tests) and a
 * markdown summary with paired two-tailed t-tests of FEM against every other method, over every seed and
 * over the pairs' means. Lengths in mm, times in s (compute only).
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationEvaluation */
class BiomechanicalRegistration_EXPORT ComparisonTables
{
public:
  explicit ComparisonTables(std::string tag);
  /** \a seconds < 0: the field was given, not computed. */
  void
  Add(const std::string &                pair,
      const std::string &                method,
      double                             seconds,
      const std::vector<bmr::Landmark> & fixedLandmarks,
      const FieldEvaluation &            evaluation);
  /** One line for a console: TRE mean +- SD (max), Dice, HD95, min J, time. */
  static std::string
  Summary(const FieldEvaluation & evaluation, double seconds);

  std::string
  PerLandmarkCsv() const;
  std::string
  PerPairCsv() const;
  std::string
  PerOrganCsv() const;
  std::string
  TTestsCsv() const;
  std::string
  SummaryMarkdown() const;

private:
  std::string                                m_Tag;
  std::string                                m_PerLandmark, m_PerPair, m_PerOrgan, m_Table;
  std::map<std::string, std::vector<double>> m_TreAll, m_TreMeans;
};

} // namespace itk

#endif
