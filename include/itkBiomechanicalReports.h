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
#ifndef itkBiomechanicalReports_h
#define itkBiomechanicalReports_h

#include "itkBiomechanicalPipelines.h"

namespace itk {

/** report.json of a registration (JSON; units: mm, kPa, mN, mm^2, s): the recovered moduli with their
 * uncertainty and one-sigma interval, the gauge, identifiability, residuals and surface distances, Dice,
 * the Jacobian of the pull-back field, inverted elements, the step limit, warnings, the mesh, the number
 * of iterations and the wall time of each stage in \a wallTimes (and their total).
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationIO */
BiomechanicalRegistration_EXPORT std::string
                                 RegistrationReportJson(const RegistrationResult &         result,
                                                        const RegistrationSettings &       settings,
                                                        const std::vector<PipelineStage> & wallTimes);

/** The inner solves \a records as CSV, one row each (E [kPa] per unknown in \a unknownNames, Phi* [mm^2],
 * |dPhi/dp|, dPhi* / dlogE [mm^2] per unknown, inner iterations, wall time [s]). \ingroup BiomechanicalRegistration
 * BiomechanicalRegistrationIO
 */
BiomechanicalRegistration_EXPORT std::string
IterationHistoryCsv(const std::vector<bmr::IterationRecord> & records, const std::vector<std::string> & unknownNames);

/** One line for a console per inner solve: stage, iteration, E [kPa], Phi* [mm^2], dPhi* / dlogE [mm^2],
 * |dPhi/dp|, inner iterations, wall time [s]. \ingroup BiomechanicalRegistration BiomechanicalRegistrationIO */
BiomechanicalRegistration_EXPORT std::string
                                 FormatIterationRecord(const bmr::IterationRecord & record);

/** The stages' wall times [s] as a table, with their total. \ingroup BiomechanicalRegistration
 * BiomechanicalRegistrationIO */
BiomechanicalRegistration_EXPORT std::string
                                 StageTable(const std::vector<PipelineStage> & stages);

/** " (fit); stated: <ModulusIntervalText>" for an unknown modulus \a label with a stated interval; else
 * " (uncertainty x/ exp(s), i.e. +-N %, one standard deviation)" when the curvature's uncertainty was computed, a
 * note when it is not determined, or empty. \ingroup BiomechanicalRegistration
 * BiomechanicalRegistrationIO */
BiomechanicalRegistration_EXPORT std::string
                                 UncertaintyText(const RegistrationResult & result, const std::string & label);

/** The recovered modulus \a label as a registration states it: "<label> <fit> kPa<UncertaintyText>", or, where no
 * modulus is stated (ModulusInterval::notDeterminedReason), ModulusIntervalText() alone, with no number but the
 * fit the fields use. \ingroup BiomechanicalRegistration BiomechanicalRegistrationIO */
BiomechanicalRegistration_EXPORT std::string
                                 RecoveredModulusText(const RegistrationResult & result, const std::string & label);

/** What the stated interval of a modulus is conditional on: the wall law of the estimation (\a walls: its motion, or
 * its trained basis). The
 * rescans vary the voxelization and the mesh, not how the walls move, and on the phantoms the wall law moved
 * the modulus by more than the interval's width (docs/history/benchmarks.md, "Pressure-filled lumens"); one sentence
 * for the printed summary and report.json's "assumes". \ingroup BiomechanicalRegistration
 * BiomechanicalRegistrationIO */
BiomechanicalRegistration_EXPORT std::string
                                 WallLawCaveat(const bmr::WallLoadSettings & walls);

/** truth.json of a phantom pair (JSON; mm, kPa, mN): the true moduli and Poisson's ratios, the tumour
 * fraction, the wall loads, the truth's mesh, the CT noise and the seed landmarks (moving and fixed).
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationIO */
BiomechanicalRegistration_EXPORT std::string
                                 PhantomTruthJson(const PhantomPair & pair, const PhantomSettings & settings);

} // namespace itk

#endif
