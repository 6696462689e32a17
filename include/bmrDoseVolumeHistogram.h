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
#ifndef bmrDoseVolumeHistogram_h
#define bmrDoseVolumeHistogram_h

#include "BiomechanicalRegistrationExport.h"

#include <cstddef>
#include <string>
#include <vector>

namespace bmr {

/** \brief The dose-volume histogram of one structure on a regular dose axis.
 *
 * Bin k covers \f$ [k w, (k+1) w) \f$ Gy with w the bin width. For N voxels of equal volume with doses
 * \f$ D_i \f$ [Gy]:
 * \f[ \mathrm{dDVH}_k = \frac{1}{N} \#\{ i : k w \le D_i < (k+1) w \}, \qquad
 *     \mathrm{cDVH}(k w) = \frac{1}{N} \#\{ i : D_i \ge k w \} = \sum_{j \ge k} \mathrm{dDVH}_j , \f]
 * both as fractions of the structure's volume (the CSV writers print percent). The cumulative DVH is
 * exact at the bin edges \f$ k w \f$ (no interpolation); cDVH(0) = 1.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationDose */
struct BiomechanicalRegistration_EXPORT DoseVolumeHistogram
{
  double              binWidth{ 0.1 }; ///< Gy
  std::vector<double> differential;    ///< fraction of the volume in bin k (sums to 1)
  std::vector<double> cumulative;      ///< fraction of the volume receiving >= k * binWidth Gy
  double              volumeCC{ 0.0 }; ///< the structure's volume [cc]
  std::size_t         numberOfVoxels{ 0 };

  /** The lower edge of bin k [Gy]. */
  double
  BinDose(std::size_t k) const
  {
    return static_cast<double>(k) * binWidth;
  }
};

/** A V-dose: the fraction of the volume receiving at least \c doseGy. */
struct BiomechanicalRegistration_EXPORT VolumeAtDose
{
  double doseGy{ 0.0 };
  double fraction{ 0.0 }; ///< in [0, 1]
};

/** \brief The dose statistics of one structure [Gy, cc].
 *
 * \c D95, \c D98, \c D2: DoseAtVolume() of 95, 98 and 2 %. \c gEUD: GeneralizedEquivalentUniformDose() with
 * the parameter \c eudA. \c volumesAtDose: VolumeAtDoses() of the requested doses.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationDose */
struct BiomechanicalRegistration_EXPORT DoseMetrics
{
  std::size_t               numberOfVoxels{ 0 };
  double                    volumeCC{ 0.0 };
  double                    mean{ 0.0 };
  double                    minimum{ 0.0 };
  double                    maximum{ 0.0 };
  double                    D95{ 0.0 };
  double                    D98{ 0.0 };
  double                    D2{ 0.0 };
  double                    eudA{ 1.0 };
  double                    gEUD{ 0.0 };
  std::vector<VolumeAtDose> volumesAtDose;
};

/** \brief The differential and cumulative DVH of the voxel doses \a dosesGy [Gy, >= 0] of one structure.
 *
 * \a voxelVolumeMM3: the volume of one voxel [mm^3] (the structure's volume is reported in cc = 1000 mm^3).
 * \a binWidthGy > 0: the bin width (0.1 Gy by default, 0.13 % of a 78 Gy prescription). The axis has
 * \f$ \lfloor \max(D_{max}, \mathrm{maximumDoseGy}) / w \rfloor + 2 \f$ bins, so that the last value of the
 * cumulative DVH is 0 and several structures can share one axis (pass the largest dose of all as
 * \a maximumDoseGy). Throws itk::ExceptionObject when \a dosesGy is empty or holds a negative or non-finite
 * dose, or when a width or volume is not positive. */
BiomechanicalRegistration_EXPORT DoseVolumeHistogram
ComputeDoseVolumeHistogram(const std::vector<double> & dosesGy,
                           double                      voxelVolumeMM3,
                           double                      binWidthGy = 0.1,
                           double                      maximumDoseGy = 0.0);

/** \brief \f$ D_x \f$: the dose [Gy] received by at least \a percent % of the volume, from the voxel doses
 * themselves (independent of any DVH binning).
 *
 * With the doses sorted in decreasing order, \f$ D_{(1)} \ge \dots \ge D_{(N)} \f$, the i-th voxel is taken to
 * stand for the volume fraction \f$ ((i-1)/N, i/N] \f$ and its dose for the middle of it,
 * \f$ p_i = (i - \tfrac12)/N \f$ (the midpoint, "Hazen", plotting position). \f$ D_x \f$ is the linear
 * interpolation of \f$ D_{(i)} \f$ in \f$ p_i \f$ at \f$ p = x/100 \f$, held at \f$ D_{(1)} \f$ for
 * \f$ p < p_1 \f$ and at \f$ D_{(N)} \f$ for \f$ p > p_N \f$. So a uniform dose gives \f$ D_x = D \f$, and the
 * doses of N voxels at the midpoints of a continuous distribution give its exact quantile wherever they
 * are distinct; voxels of equal dose (ties) stand for one dose, which is off the continuous quantile by at
 * most half the dose step between two consecutive groups. \a percent in [0, 100]. */
BiomechanicalRegistration_EXPORT double
DoseAtVolume(std::vector<double> dosesGy, double percent);

/** \brief \f$ V_x \f$ for each dose of \a thresholdsGy: the fraction of the voxels with
 * \f$ D_i \ge x \f$ (exact; no binning). */
BiomechanicalRegistration_EXPORT std::vector<VolumeAtDose>
VolumeAtDoses(const std::vector<double> & dosesGy, const std::vector<double> & thresholdsGy);

/** \brief Niemierko's generalized equivalent uniform dose [Gy] of the voxel doses \a dosesGy:
 * \f[ \mathrm{gEUD} = \Big( \sum_i v_i D_i^{\,a} \Big)^{1/a}, \qquad v_i = 1/N \f]
 * (equal voxel volumes; \f$ v_i \f$ the fractional volumes).
 *
 * a = 1 gives the mean dose; a -> +inf the maximum (serial organs: large a); a -> -inf the minimum
 * (targets: negative a penalizes cold spots). The limit a -> 0 is the geometric mean
 * \f$ \exp(\sum_i v_i \ln D_i) \f$, which is returned for a = 0. For a < 0 (and a = 0) a voxel with
 * \f$ D_i = 0 \f$ makes the sum infinite and gEUD = 0 exactly (its limit), returned without forming
 * \f$ 0^a \f$. The sum is formed relative to the largest (a > 0) or smallest (a < 0) dose, so
 * \f$ (D_i/D_{ref})^a \le 1 \f$ never overflows for |a| up to hundreds, and a uniform dose returns D exactly.
 * Throws itk::ExceptionObject on an empty input, a negative or non-finite dose, or a non-finite a. */
BiomechanicalRegistration_EXPORT double
GeneralizedEquivalentUniformDose(const std::vector<double> & dosesGy, double a);

/** \brief The default gEUD parameter a of a structure, by its name (case-insensitive); a default only,
 * every caller can override it.
 *
 * - Targets ("prostate", "ptv", "ctv", "gtv", "target", and names containing them): a = -10, the value
 *   commonly used for prostate targets in gEUD-based planning (e.g. Wu et al. 2002): cold spots dominate.
 * - Rectum and anterior rectal wall (names containing "rect"): a = 8, at the lower end of the 8-12 used for the
 *   rectum in gEUD planning and NTCP fits (a = 1/n of the Lyman-Kutcher-Burman volume parameter: n = 0.12,
 *   Burman et al. 1991, gives a = 8.3; n = 0.09, QUANTEC, Michalski et al. 2010, gives a = 11): a serial
 *   organ, whose complication risk follows the high doses.
 * - Bladder ("bladder"): a = 2, from the LKB volume parameter n = 0.5 of Burman et al. 1991 (a = 1/n): a
 *   more parallel response, close to the mean dose.
 * - Every other name: a = 1, the mean dose. */
BiomechanicalRegistration_EXPORT double
DefaultEudParameter(const std::string & structureName);

/** \brief Every metric of DoseMetrics for the voxel doses \a dosesGy [Gy] of one structure of voxels of
 * \a voxelVolumeMM3 [mm^3]: mean, minimum, maximum, D95, D98, D2 (DoseAtVolume()), the V-doses of
 * \a thresholdsGy (VolumeAtDoses()) and the gEUD with parameter \a eudA. Throws as
 * ComputeDoseVolumeHistogram(). */
BiomechanicalRegistration_EXPORT DoseMetrics
ComputeDoseMetrics(const std::vector<double> & dosesGy,
                   double                      voxelVolumeMM3,
                   double                      eudA,
                   const std::vector<double> & thresholdsGy = std::vector<double>());

} // namespace bmr

#endif
