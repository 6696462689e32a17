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
#ifndef itkDoseEvaluation_h
#define itkDoseEvaluation_h

#include "bmrDoseVolumeHistogram.h"
#include "bmrScene.h"
#include "itkImage.h"
#include "itkVector.h"

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace itk {

// Dose on label maps (Doxygen group BiomechanicalRegistrationDose): per-structure DVHs and metrics, the anterior
// rectal wall, a synthetic conformal plan, and warping a dose through a displacement field. Doses in Gy, lengths
// in mm (LPS), volumes in cc.

/** The image types of the dose functions: dose [Gy, float], label maps (int32, as the pipelines' label maps),
 * fixed -> moving displacement fields [mm]. \ingroup BiomechanicalRegistration BiomechanicalRegistrationDose */
using BiomechanicalDoseImageType = Image<float, 3>;
using DoseLabelImageType = Image<std::int32_t, 3>;
using DoseDisplacementFieldType = Image<Vector<double, 3>, 3>;
using DoseMaskImageType = Image<unsigned char, 3>;

/** \brief How the anterior rectal wall is derived from a label map (AnteriorRectalWallMask()).
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationDose */
struct BiomechanicalRegistration_EXPORT AnteriorRectalWallSettings
{
  std::string name{ "anterior_rectal_wall" }; ///< the structure's name in the tables
  std::string rectumName{ "rectum" };         ///< the organ it is derived from
  std::string prostateName{ "prostate" };     ///< the organ it faces
  double      wallThicknessMm{ 3.0 };         ///< depth of the shell below the rectum's surface [mm]
  double      prostateDistanceMm{ 15.0 };     ///< largest distance from the prostate's surface [mm]
};

/** \brief The anterior rectal wall of a label map: 1 on its voxels, 0 elsewhere, on the label grid.
 *
 * A label map holds the rectum as a solid (the pelvis phantom's rectum label includes the gas-filled lumen,
 * as clinical contours of the outer rectal wall do), so the wall is derived: the voxels of \a rectumLabel
 * whose depth below the rectum's surface is at most \a wallThicknessMm (the outer shell; 3 mm is the
 * thickness of the distended rectal wall), and whose distance to the surface of \a prostateLabel is at most
 * \a prostateDistanceMm — the part of the shell that faces the prostate. Depth and distance are the signed
 * distances [mm] to the faces of the organs' voxels (Maurer's map of the mask and of its complement,
 * averaged: physical units, any grid orientation). With the default 15 mm and the phantom's 13 mm rectum
 * 4 mm behind the prostate, the wall is the anterior ~160 degrees of the rectal circumference, over the
 * prostate's cranio-caudal extent plus about 1 cm; the posterior wall lies 30 mm or more from the prostate.
 * Throws itk::ExceptionObject when either label is absent or a length is not positive. */
BiomechanicalRegistration_EXPORT DoseMaskImageType::Pointer
                                 AnteriorRectalWallMask(const DoseLabelImageType * labels,
                                                        std::int32_t               rectumLabel,
                                                        std::int32_t               prostateLabel,
                                                        double                     wallThicknessMm = 3.0,
                                                        double                     prostateDistanceMm = 15.0);

/** \brief What EvaluateDose() computes per structure.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationDose */
struct BiomechanicalRegistration_EXPORT DoseEvaluationSettings
{
  double binWidthGy{ 0.1 }; ///< DVH bin width [Gy]
  /** The V-doses [Gy] of every structure: the QUANTEC rectal dose-volume limits for conventional
   * fractionation (V50 < 50 %, V60 < 35 %, V65 < 25 %, V70 < 20 %, V75 < 15 %; Michalski et al. 2010). */
  std::vector<double> volumeDosesGy{ 50.0, 60.0, 65.0, 70.0, 75.0 };
  /** gEUD parameter a per structure name; the others get bmr::DefaultEudParameter(name). */
  std::map<std::string, double> eudParameters;
  /** Add the anterior rectal wall (when both of its organs are among the structures). */
  bool                       anteriorRectalWall{ true };
  AnteriorRectalWallSettings wall;
};

/** The dose of one structure: its name, its label (-1 for a derived structure such as the anterior rectal
 * wall), its DVH and metrics, and the fraction [0, 1] of its voxels outside the dose grid (given 0 Gy).
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationDose */
struct BiomechanicalRegistration_EXPORT StructureDose
{
  std::string              name;
  std::int32_t             label{ -1 };
  bmr::DoseMetrics         metrics;
  bmr::DoseVolumeHistogram dvh;
  double                   fractionOutsideDoseGrid{ 0.0 };
};

/** Every structure's dose, in the order of the structure map (by name) with the derived structures last;
 * all DVHs share one dose axis. \ingroup BiomechanicalRegistration BiomechanicalRegistrationDose */
struct BiomechanicalRegistration_EXPORT DoseEvaluation
{
  std::vector<StructureDose> structures;
  double                     binWidthGy{ 0.1 };
  std::vector<double>        volumeDosesGy;
  bool                       doseResampled{ false }; ///< the dose grid differed from the label grid

  /** The structure called \a name; throws itk::ExceptionObject when there is none. */
  const StructureDose &
  Find(const std::string & name) const;
};

/** The structures of a scene for EvaluateDose(): name -> label value of every label whose role is not
 * "outside" (air and background have no dose of interest).
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationDose */
BiomechanicalRegistration_EXPORT std::map<std::string, std::int32_t>
                                 DoseStructuresFromScene(const bmr::Scene & scene);

/** \brief \a dose [Gy] on the grid of \a reference: linear interpolation (itk::ResampleImageFilter with
 * itk::LinearInterpolateImageFunction, identity transform, in physical space); points outside the dose grid
 * get 0 Gy. When the grids are equal (size, origin, spacing and direction within 1e-6 mm / 1e-9) the result
 * shares \a dose's buffer (no copy). Dose grids (RTDOSE: typically 2-4 mm) are coarser than the CT's and smooth on that
 * scale, which is why linear interpolation is the clinical standard for them.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationDose */
BiomechanicalRegistration_EXPORT BiomechanicalDoseImageType::Pointer
ResampleDoseOntoGrid(const BiomechanicalDoseImageType * dose, const ImageBase<3> * reference);

/** \brief Per structure of \a labels, the DVH and the metrics of \a dose [Gy].
 *
 * \a structures: name -> label value (DoseStructuresFromScene(), or the caller's own). When the dose grid
 * differs from the label grid the dose is first resampled linearly onto the label grid
 * (ResampleDoseOntoGrid()); the voxels of a structure that lie outside the dose grid count as 0 Gy and their
 * fraction is reported. Voxel volume: the product of the label grid's spacing [mm^3]. With
 * \c settings.anteriorRectalWall and both \c settings.wall.rectumName and \c settings.wall.prostateName among
 * the structures, the anterior rectal wall (AnteriorRectalWallMask()) is added as a structure of its own.
 * Throws itk::ExceptionObject naming the structure when a label of \a structures is absent from \a labels,
 * and when the dose holds a negative or non-finite value inside a structure. */
BiomechanicalRegistration_EXPORT DoseEvaluation
EvaluateDose(const DoseLabelImageType *                  labels,
             const BiomechanicalDoseImageType *          dose,
             const std::map<std::string, std::int32_t> & structures,
             const DoseEvaluationSettings &              settings = DoseEvaluationSettings());

/** \brief The DVH table: one row per bin, the columns \c dose_Gy (the bin's lower edge) and, per structure,
 * \c <name>_cumulative_pct (% of the volume receiving >= dose_Gy) and \c <name>_differential_pct (% of the
 * volume in [dose_Gy, dose_Gy + bin width)). \ingroup BiomechanicalRegistration BiomechanicalRegistrationDose */
BiomechanicalRegistration_EXPORT std::string
                                 DoseVolumeHistogramCsv(const DoseEvaluation & evaluation);

/** \brief The metrics table: one row per structure, the columns \c organ, \c a, \c gEUD_Gy, \c Dmean_Gy,
 * \c D95_Gy, \c D2_Gy, \c D98_Gy, \c Dmin_Gy, \c Dmax_Gy, \c V<x>Gy_pct per V-dose, \c volume_cc, \c voxels,
 * \c outside_dose_grid_pct. \ingroup BiomechanicalRegistration BiomechanicalRegistrationDose */
BiomechanicalRegistration_EXPORT std::string
                                 DoseMetricsCsv(const DoseEvaluation & evaluation);

/** Writes \a directory/dvh.csv and \a directory/dose_metrics.csv, each through a temporary file renamed when
 * complete (bmr::WriteTextFileAtomically); \a directory must exist.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationDose */
BiomechanicalRegistration_EXPORT void
WriteDoseEvaluation(const std::string & directory, const DoseEvaluation & evaluation);

/** \brief A synthetic conformal plan (MakeConformalDosePlan()).
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationDose */
struct BiomechanicalRegistration_EXPORT ConformalPlanSettings
{
  double marginMm{ 5.0 };        ///< PTV = prostate expanded isotropically by this [mm], >= 0
  double prescriptionGy{ 78.0 }; ///< Rx [Gy]: the dose deep inside the PTV (78 Gy in 39 fractions)
  /** 80-20 % width of the dose edge [mm]. 6 mm: the penumbra of a 6 MV MLC-shaped field at depth is
   * 5-8 mm, and the fall-off of a conformal / IMRT / VMAT prostate plan outside its PTV is of that order. */
  double penumbraMm{ 6.0 };
  /** Optional low-dose bath: the fraction f of Rx reached just outside the PTV by the overlap of beams,
   * decaying as exp(-d / bathLengthMm) (0: no bath). */
  double bathFraction{ 0.0 };
  double bathLengthMm{ 30.0 }; ///< decay length of the bath [mm]
};

/** \brief The Gaussian width sigma [mm] of an erfc dose edge whose 80-20 % width is \a penumbraMm:
 * \f$ \sigma = w_{80-20} / (2 \Phi^{-1}(0.8)) = w_{80-20} / (2 \cdot 0.8416) \f$.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationDose */
BiomechanicalRegistration_EXPORT double
PenumbraSigma(double penumbraMm);

/** \brief A synthetic conformal dose [Gy] on the grid of \a labels: the prescription inside the PTV with an
 * erfc penumbra.
 *
 * With \f$ s(x) \f$ the signed distance [mm, negative inside] to the surface of \a prostateLabel (the faces of
 * its voxels: itk::SignedMaurerDistanceMapImageFilter of the mask and of its complement, averaged, in
 * physical units), the PTV is \f$ \{ s \le m \} \f$, m = \c marginMm, and \f$ d = s - m \f$ is the signed
 * distance to the PTV surface (exact outside the PTV; inside it wherever the nearest PTV surface point lies
 * along the prostate's normal, as for a convex prostate). The dose is a half-space edge blurred by a Gaussian
 * of width sigma (the lateral scatter and source size that make a beam's penumbra):
 * \f[ D(x) = R_x \tfrac12 \operatorname{erfc}\!\Big( \frac{d(x)}{\sqrt{2}\,\sigma} \Big), \qquad
 *     \sigma = \frac{w_{80-20}}{2 \cdot 0.8416} \f]
 * so D = Rx/2 on the PTV surface, the dose falls from 80 % to 20 % of Rx over \c penumbraMm, and inside the
 * prostate (d <= -m) \f$ D \ge R_x \Phi(m/\sigma) \f$: 0.92 Rx at 5 mm, 0.98 Rx at m = 2 sigma (7.1 mm for
 * the default 6 mm penumbra). With a bath fraction f > 0, \f$ D \leftarrow D + f R_x (1 - D/R_x)
 * e^{-\max(d,0)/\lambda} \f$: unchanged deep inside, f Rx e^{-d/lambda} far outside. Throws
 * itk::ExceptionObject when the prostate label is absent or a setting is out of range (margin < 0 or > 50 mm,
 * Rx <= 0, penumbra <= 0, bath fraction outside [0, 1), bath length <= 0).
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationDose */
BiomechanicalRegistration_EXPORT BiomechanicalDoseImageType::Pointer
                                 MakeConformalDosePlan(const DoseLabelImageType *    labels,
                                                       std::int32_t                  prostateLabel,
                                                       const ConformalPlanSettings & settings = ConformalPlanSettings());

/** \brief \a dose [Gy] warped through the fixed -> moving \a field: out(x) = dose(x + d(x)) on the field's
 * grid, linear interpolation (itk::ImageWarper), 0 Gy where x + d(x) falls outside the dose grid.
 *
 * The field's convention (README): it maps points of the fixed grid to the moving image, so the result is
 * the dose of the moving image's anatomy carried onto the fixed anatomy, voxel by voxel of tissue. Use: dose
 * accumulation — a treatment-day dose (moving) onto the planning anatomy (fixed) with the planning ->
 * treatment field. (Under the static dose-cloud approximation the dose delivered on a treatment day is the
 * planned dose where it lies in the room; evaluate it with that day's labels, no warp needed.)
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationDose */
BiomechanicalRegistration_EXPORT BiomechanicalDoseImageType::Pointer
WarpDose(const BiomechanicalDoseImageType * dose, const DoseDisplacementFieldType * field);

} // namespace itk

#endif
