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
#ifndef itkMarkerPipeline_h
#define itkMarkerPipeline_h

#include "itkBiomechanicalPipelines.h"

#include "bmrLandmarks.h"

#include <array>

namespace itk {

/** Settings of EstimateTreatmentFromMarkers(); the defaults are biomechreg markers'.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
struct BiomechanicalRegistration_EXPORT MarkerSettings
{
  std::string organ{ "prostate" };   ///< scene label whose surface carries the unknown forces
  double      boxMargin{ 25.0 };     ///< mm: the static box is the organ's bounding box widened by this
  double      controlSpacing{ 8.0 }; ///< mm between the force basis' control points on the organ surface
  /** alpha [1] of the prior alpha/2 |q|^2 on the surface loads (bmr::OrganSurfaceForces; q reads as mm). */
  double regularization{ 1e-3 };
  double meshScale{ 1.0 }; ///< the scene's mesh sizes times this
  /** Moduli [kPa] by scene label name; a label the scene leaves unknown needs none: its initial value is used
   * (and said in a warning). */
  std::map<std::string, double> moduli;
  unsigned int                  maximumIterations{ 30 };
  bool                          leaveOneOut{ true }; ///< refit without each marker (>= 3 markers)
};

/** One way of carrying the planning anatomy to treatment from the markers: FEM, rigid or thin-plate spline.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
struct BiomechanicalRegistration_EXPORT MarkerMethodResult
{
  std::string         method;
  std::vector<double> fitResidual;            ///< per marker, fitted to all [mm]
  std::vector<double> leaveOneOutError;       ///< per marker, fitted to the others [mm]
  double              leaveOneOutRms{ -1.0 }; ///< mm; < 0 when not computed
  /** Per marker, where the method fitted to the others puts it [mm, treatment frame]; empty when not computed. */
  std::vector<std::array<double, 3>> leaveOneOutPrediction;
  /** The same predictions against the markers' true treatment positions, without their tracking noise
   * (EvaluateLeaveOneOutAgainstTruth(), phantoms): per marker [mm] and RMS [mm]; < 0 when not evaluated. */
  std::vector<double>                  leaveOneOutTrueError;
  double                               leaveOneOutTrueRms{ -1.0 };
  BiomechanicalFieldType::Pointer      field;        ///< treatment -> planning [mm] on the planning grid
  BiomechanicalLabelImageType::Pointer warpedLabels; ///< the estimated treatment labels
  /** Against the real treatment labels (EvaluateMarkerMethods()): the organ's intersection over union and the
   * mean one-sided surface distance D [mm] from the real organ's surface to the estimated one (Table 4.1);
   * < 0 when not evaluated. */
  double intersectionOverUnion{ -1.0 };
  double meanSurfaceDistance{ -1.0 };
};

/** What EstimateTreatmentFromMarkers() found. \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
struct BiomechanicalRegistration_EXPORT MarkerResult
{
  SimulationResult                  state;     ///< the box mesh with the FEM displacement, the pull-back field
  BiomechanicalCTImageType::Pointer warpedCT;  ///< the estimated treatment CT (FEM)
  std::vector<std::string>          markerIds; ///< in the order of every per-marker list
  std::vector<MarkerMethodResult>   methods;   ///< "fem", "rigid", "tps"
  std::size_t                       loadParameters{ 0 }, surfaceNodes{ 0 }, heldNodes{ 0 };
  double                            forceScale{ 0.0 }; ///< kappa [mN per unit parameter]
  std::vector<double>               surfaceForces;     ///< 3N nodal forces of the FEM fit [mN]
  unsigned int                      iterations{ 0 };
  std::map<std::string, double>     moduli; ///< kPa, what the model assumed per label
  std::vector<std::string>          warnings;
  std::vector<PipelineStage>        stages;
};

/** \brief Marker-driven deformation (dissertation chapter 4): the planning anatomy deformed by the finite element
 * model until its implanted markers land on their tracked treatment positions.
 *
 * The planning labels are cropped to a static box (the organ's bounding box widened by MarkerSettings::boxMargin)
 * and meshed; the box faces and the bone are held (u = 0), hollow organs' walls are free, and the unknown loads are
 * forces on the organ's surface (bmr::OrganSurfaceForces) found by Levenberg-Marquardt on the landmark term
 * (bmr::LandmarkTerm, markers located by barycentric coordinates). Markers are paired by id. The same markers also
 * give the two references a clinic would use: the least-squares rigid motion (bmr::FitRigidTransform) and the
 * thin-plate spline (bmr::ThinPlateSpline, fitted from treatment to planning so that it is itself the pull-back).
 * With three or more markers each method is refitted without each marker in turn and predicts it (leave-one-out
 * TRE). Fields map treatment points to planning points on the planning grid; the estimated treatment CT and labels
 * are the planning ones warped by the FEM field. Throws, naming the input, when the labels lack the organ, an id has
 * no partner, fewer than two markers are given, or a marker lies outside the box.
 * Units: mm, kPa, mN. \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
BiomechanicalRegistration_EXPORT MarkerResult
EstimateTreatmentFromMarkers(const BiomechanicalLabelImageType * planningLabels,
                             const BiomechanicalCTImageType *    planningCT,
                             const bmr::Scene &                  scene,
                             const std::vector<bmr::Landmark> &  planningMarkers,
                             const std::vector<bmr::Landmark> &  treatmentMarkers,
                             const MarkerSettings &              settings = MarkerSettings(),
                             PipelineObserver *                  observer = nullptr);

/** Fills every method's intersectionOverUnion and meanSurfaceDistance for \a organLabel against the real
 * \a treatmentLabels (on the planning grid: throws otherwise). \ingroup BiomechanicalRegistrationPipelines */
BiomechanicalRegistration_EXPORT void
EvaluateMarkerMethods(MarkerResult &                      result,
                      const BiomechanicalLabelImageType * treatmentLabels,
                      std::int32_t                        organLabel);

/** Fills every method's leaveOneOutTrueError and leaveOneOutTrueRms: the distance [mm] of each leave-one-out
 * prediction from that marker's true treatment position in \a trueTreatmentMarkers (paired by id; a phantom's
 * noise-free seeds), where leaveOneOutError measures it against the tracked position, whose noise is in every
 * method's error alike. Does nothing without leave-one-out; otherwise throws, naming the marker, when one is
 * missing (markers the result does not hold are ignored).
 * \ingroup BiomechanicalRegistrationPipelines */
BiomechanicalRegistration_EXPORT void
EvaluateLeaveOneOutAgainstTruth(MarkerResult & result, const std::vector<bmr::Landmark> & trueTreatmentMarkers);

/** report.json of a marker run (units in the keys). \ingroup BiomechanicalRegistrationPipelines */
BiomechanicalRegistration_EXPORT std::string
                                 MarkerReportJson(const MarkerResult & result, const MarkerSettings & settings);

/** \a markers with independent Gaussian tracking noise of \a sigma [mm] on every coordinate, seeded by \a seed
 * (the same seed gives the same noise on every platform). \ingroup BiomechanicalRegistrationPipelines */
BiomechanicalRegistration_EXPORT std::vector<bmr::Landmark>
                                 AddTrackingNoise(std::vector<bmr::Landmark> markers, double sigma, std::uint64_t seed);

} // namespace itk

#endif
