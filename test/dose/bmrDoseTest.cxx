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
// Dose (bmrDoseVolumeHistogram.h, itkDoseEvaluation.h):
// - gEUD against closed forms: a uniform dose for any a, two dose levels by hand, a = 1 the mean, the power-mean
//   bounds towards the maximum (a -> +inf) and the minimum (a -> -inf), monotone in a, D = 0 with a <= 0;
// - the DVH, D95 / D2 / D98 and Dmean of a dose linear in x over a box of voxels (uniform dose distribution);
// - the conformal plan: the closed form along a profile from a box face, Rx/2 on the PTV surface, the 80-20 %
//   width equal to the penumbra, margins in mm on an anisotropic grid, Dmin >= Rx Phi(m / sigma) and D95
//   increasing towards Rx over the margins 5 ... 13 mm on the pelvis phantom;
// - the anterior rectal wall of the pelvis phantom against its analytic rectum;
// - a dose on another grid (resampled), partly outside it, a warped dose, the CSV tables, the refused inputs.
#include "bmrDoseVolumeHistogram.h"
#include "bmrPhantom.h"
#include "bmrTestUtilities.h"
#include "itkDoseEvaluation.h"
#include "itkGridGeometryConversion.h"
#include "itkImageRegionIteratorWithIndex.h"
#include "itkMacro.h"
#include "itkTestingMacros.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace {

using bmr::test::Expect;
using bmr::test::ToString;
using DoseImage = itk::BiomechanicalDoseImageType;
using LabelImage = itk::DoseLabelImageType;

bool
Near(double value, double expected, double tolerance, const std::string & what)
{
  return Expect(std::abs(value - expected) <= tolerance,
                what + ": " + ToString(value) + ", expected " + ToString(expected) + " +- " + ToString(tolerance));
}

double
NormalCdf(double x)
{
  return 0.5 * std::erfc(-x / std::sqrt(2.0));
}

/** An image of \a size voxels of \a spacing [mm] at \a origin, identity direction, filled with \a value. */
template<typename TImage>
typename TImage::Pointer
MakeImage(const std::array<std::size_t, 3> & size,
          const std::array<double, 3> &      spacing,
          const std::array<double, 3> &      origin,
          typename TImage::PixelType         value)
{
  bmr::GridGeometry grid;
  grid.size = size;
  grid.spacing = spacing;
  grid.origin = origin;
  return itk::MakeImageOnGrid<TImage>(grid, std::vector<typename TImage::PixelType>(grid.GetNumberOfVoxels(), value));
}

/** Sets every voxel of \a image to f(physical point). */
template<typename TImage, typename F>
void
Fill(TImage * image, F f)
{
  for (itk::ImageRegionIteratorWithIndex<TImage> it(image, image->GetLargestPossibleRegion()); !it.IsAtEnd(); ++it)
  {
    typename TImage::PointType x;
    image->TransformIndexToPhysicalPoint(it.GetIndex(), x);
    it.Set(f(x));
  }
}

/** A deterministic sequence in [lo, hi) (LCG of Numerical Recipes): test data without <random>'s
 * implementation-defined distributions. */
std::vector<double>
PseudoRandomDoses(std::size_t n, double lo, double hi)
{
  std::vector<double> doses;
  std::uint32_t       state = 12345u;
  for (std::size_t i = 0; i < n; ++i)
  {
    state = 1664525u * state + 1013904223u;
    doses.push_back(lo + (hi - lo) * static_cast<double>(state) / 4294967296.0);
  }
  return doses;
}

// ------------------------------------------------------------------ gEUD

bool
TestEquivalentUniformDose()
{
  bool ok = true;
  // A uniform dose D is its own gEUD for every a: every term (D/D)^a is exactly 1 (tolerance 1e-12 Gy).
  const std::vector<double> uniform(1000, 70.3);
  for (const double a : { -40.0, -10.0, -1.0, 0.0, 0.5, 1.0, 8.0, 40.0 })
  {
    ok &=
      Near(bmr::GeneralizedEquivalentUniformDose(uniform, a), 70.3, 1e-12, "gEUD of a uniform dose, a " + ToString(a));
  }
  // Two dose levels: 3 of 10 voxels at 20 Gy, 7 at 70 Gy, by hand (v1 D1^a + v2 D2^a)^(1/a) without the
  // rescaling the implementation does: only rounding differs (relative 1e-12).
  std::vector<double> twoLevels(3, 20.0);
  twoLevels.insert(twoLevels.end(), 7, 70.0);
  for (const double a : { -10.0, -1.0, 1.0, 2.0, 8.0, 12.0 })
  {
    const double byHand = std::pow(0.3 * std::pow(20.0, a) + 0.7 * std::pow(70.0, a), 1.0 / a);
    ok &= Near(bmr::GeneralizedEquivalentUniformDose(twoLevels, a),
               byHand,
               1e-12 * byHand,
               "gEUD of two dose levels, a " + ToString(a));
  }
  // a = 1 is the mean dose (relative 1e-12: sums of 500 terms in two orders).
  const std::vector<double> doses = PseudoRandomDoses(500, 10.0, 80.0);
  double                    mean = 0.0;
  for (const double d : doses)
  {
    mean += d / static_cast<double>(doses.size());
  }
  ok &= Near(bmr::GeneralizedEquivalentUniformDose(doses, 1.0), mean, 1e-12 * mean, "gEUD with a = 1 (the mean)");
  // The power mean lies between the extremes and tends to them: for a > 0, (1/N)^(1/a) max <= gEUD <= max (the
  // largest voxel alone is 1/N of the volume); for a < 0, min <= gEUD <= (1/N)^(1/a) min. No tolerance: bounds.
  const double n = static_cast<double>(doses.size());
  const double maximum = *std::max_element(doses.begin(), doses.end());
  const double minimum = *std::min_element(doses.begin(), doses.end());
  for (const double a : { 200.0, 1000.0 })
  {
    const double g = bmr::GeneralizedEquivalentUniformDose(doses, a);
    ok &= Expect(g <= maximum * (1.0 + 1e-15) && g >= std::pow(1.0 / n, 1.0 / a) * maximum,
                 "gEUD with a " + ToString(a) + " in [(1/N)^(1/a) max, max]: " + ToString(g) + ", max " +
                   ToString(maximum));
    const double h = bmr::GeneralizedEquivalentUniformDose(doses, -a);
    ok &= Expect(h >= minimum * (1.0 - 1e-15) && h <= std::pow(1.0 / n, -1.0 / a) * minimum,
                 "gEUD with a " + ToString(-a) + " in [min, (1/N)^(1/a) min]: " + ToString(h) + ", min " +
                   ToString(minimum));
  }
  ok &= Near(bmr::GeneralizedEquivalentUniformDose(doses, 1000.0),
             maximum,
             0.01 * maximum,
             "gEUD with a = 1000 within 1 % of the maximum (the bound above: 1 - 500^(-1/1000) = 0.62 %)");
  // The power mean increases with a (strictly, for unequal doses).
  double previous = 0.0;
  for (const double a : { -40.0, -10.0, -1.0, 0.0, 1.0, 2.0, 8.0, 12.0, 40.0 })
  {
    const double g = bmr::GeneralizedEquivalentUniformDose(doses, a);
    ok &= Expect(g > previous,
                 "gEUD increases with a: a " + ToString(a) + " gives " + ToString(g) + " after " + ToString(previous));
    previous = g;
  }
  // A voxel without dose and a <= 0: the sum of D^a is infinite and gEUD = 0 exactly, not NaN.
  std::vector<double> cold = doses;
  cold[17] = 0.0;
  for (const double a : { -10.0, -0.5, 0.0 })
  {
    const double g = bmr::GeneralizedEquivalentUniformDose(cold, a);
    ok &= Expect(g == 0.0 && !std::isnan(g), "gEUD with a zero-dose voxel and a " + ToString(a) + ": " + ToString(g));
  }
  const double warm = bmr::GeneralizedEquivalentUniformDose(cold, 8.0);
  ok &= Expect(std::isfinite(warm) && warm > 0.0, "gEUD with a zero-dose voxel and a = 8 is finite: " + ToString(warm));
  ok &= Expect(bmr::GeneralizedEquivalentUniformDose(std::vector<double>(5, 0.0), 8.0) == 0.0, "gEUD of no dose");
  // Documented defaults.
  ok &= Expect(bmr::DefaultEudParameter("prostate") == -10.0 && bmr::DefaultEudParameter("PTV_78") == -10.0 &&
                 bmr::DefaultEudParameter("rectum") == 8.0 && bmr::DefaultEudParameter("anterior_rectal_wall") == 8.0 &&
                 bmr::DefaultEudParameter("Bladder") == 2.0 && bmr::DefaultEudParameter("soft_tissue") == 1.0,
               "the default a per structure name");
  return ok;
}

// ------------------------------------------------------------------ DVH of a dose linear in x

/** A box of 700 x 4 x 4 voxels of 1 mm with the dose 0.1 Gy/mm * x: column i gets (i + 1/2) 0.1 Gy, the middle of
 * bin i of a 0.1 Gy axis. The voxels sample the uniform distribution on [0, G], G = 70 Gy, whose cumulative DVH is
 * V(d) = 1 - d / G, D_x = (1 - x/100) G and mean G/2. */
bool
TestLinearDoseHistogram()
{
  bool         ok = true;
  const double w = 0.1;
  const double G = 70.0;
  const auto   labels = MakeImage<LabelImage>({ { 700, 4, 4 } }, { { 1, 1, 1 } }, { { 0.5, 0.5, 0.5 } }, 1);
  const auto   dose = MakeImage<DoseImage>({ { 700, 4, 4 } }, { { 1, 1, 1 } }, { { 0.5, 0.5, 0.5 } }, 0.0f);
  Fill(dose.GetPointer(), [w](const DoseImage::PointType & x) { return static_cast<float>(w * x[0]); });
  itk::DoseEvaluationSettings settings;
  settings.volumeDosesGy = { 7.0, 35.0, 63.0 };
  const itk::DoseEvaluation  evaluation = itk::EvaluateDose(labels, dose, { { "box", 1 } }, settings);
  const itk::StructureDose & box = evaluation.Find("box");
  ok &= Expect(!evaluation.doseResampled, "the dose on the label grid is not resampled");
  // Cumulative DVH at the edges k w: the columns i >= k, (700 - k)/700 = 1 - k w / G. Exact integer counts
  // divided once: 1e-12.
  const auto & dvh = box.dvh;
  ok &= Expect(dvh.cumulative.size() == 701,
               "700 bins up to 70 Gy plus the empty last one: " + ToString(dvh.cumulative.size()));
  double worst = 0.0, differentialWorst = 0.0;
  for (std::size_t k = 0; k <= 700; ++k)
  {
    worst = std::max(worst, std::abs(dvh.cumulative[k] - (1.0 - dvh.BinDose(k) / G)));
  }
  for (std::size_t k = 0; k < 700; ++k)
  {
    differentialWorst = std::max(differentialWorst, std::abs(dvh.differential[k] - 1.0 / 700.0));
  }
  ok &= Near(worst, 0.0, 1e-12, "cumulative DVH of a linear dose = 1 - d/G at every bin edge");
  ok &= Near(differentialWorst, 0.0, 1e-15, "differential DVH: 1/700 of the volume per bin");
  ok &= Expect(dvh.cumulative.back() == 0.0 && dvh.cumulative.front() == 1.0, "cDVH from 1 to 0");
  ok &= Near(dvh.volumeCC, 11.2, 1e-12, "volume 700 x 4 x 4 mm^3 = 11.2 cc");
  // D_x from the continuous distribution: D95 = 0.05 G, D2 = 0.98 G, D98 = 0.02 G. Within half a bin (0.05 Gy):
  // the 16 voxels of a column share one dose and stand for 1/700 of the volume that the continuous dose spreads
  // over one bin; the midpoint interpolation puts them at the column's middle, off by at most half a bin.
  const bmr::DoseMetrics & m = box.metrics;
  ok &= Near(m.D95, 0.05 * G, 0.5 * w, "D95 of a linear dose");
  ok &= Near(m.D2, 0.98 * G, 0.5 * w, "D2 of a linear dose");
  ok &= Near(m.D98, 0.02 * G, 0.5 * w, "D98 of a linear dose");
  // The mean of the column midpoints is exactly G/2 (float storage of 0.1 i: 1e-5 Gy).
  ok &= Near(m.mean, 0.5 * G, 1e-5, "Dmean of a linear dose");
  ok &= Near(m.minimum, 0.05, 1e-6, "Dmin = the first column's dose");
  ok &= Near(m.maximum, 69.95, 1e-5, "Dmax = the last column's dose");
  // V-doses: columns with (i + 1/2) w >= x, counted exactly.
  ok &= Near(m.volumesAtDose[0].fraction, 630.0 / 700.0, 1e-15, "V7Gy");
  ok &= Near(m.volumesAtDose[1].fraction, 350.0 / 700.0, 1e-15, "V35Gy");
  ok &= Near(m.volumesAtDose[2].fraction, 70.0 / 700.0, 1e-15, "V63Gy");
  // gEUD with a = 1 is the mean; the structure "box" has the default a = 1.
  ok &= Near(m.eudA, 1.0, 0.0, "default a of an unnamed structure") & Near(m.gEUD, m.mean, 1e-9, "gEUD(a=1) = Dmean");
  // D_x of a uniform dose, and of a few voxels by the stated interpolation (doses 40, 30, 20, 10 at p = 1/8, 3/8,
  // 5/8, 7/8): D50 halfway between 30 and 20, D5 held at the maximum, D100 at the minimum.
  ok &= Near(bmr::DoseAtVolume(std::vector<double>(9, 77.0), 95.0), 77.0, 0.0, "D95 of a uniform dose");
  ok &= Near(bmr::DoseAtVolume({ 10, 40, 20, 30 }, 50.0), 25.0, 1e-12, "D50 of four voxels");
  ok &= Near(bmr::DoseAtVolume({ 10, 40, 20, 30 }, 25.0), 35.0, 1e-12, "D25 of four voxels");
  ok &= Near(bmr::DoseAtVolume({ 10, 40, 20, 30 }, 5.0), 40.0, 0.0, "D5 of four voxels");
  ok &= Near(bmr::DoseAtVolume({ 10, 40, 20, 30 }, 100.0), 10.0, 0.0, "D100 of four voxels");
  return ok;
}

// ------------------------------------------------------------------ the conformal plan

/** Linear interpolation of the position where \a values (at \a positions, decreasing values) cross \a level. */
double
Crossing(const std::vector<double> & positions, const std::vector<double> & values, double level)
{
  for (std::size_t i = 0; i + 1 < values.size(); ++i)
  {
    if (values[i] >= level && values[i + 1] < level)
    {
      return positions[i] + (positions[i + 1] - positions[i]) * (values[i] - level) / (values[i] - values[i + 1]);
    }
  }
  return std::numeric_limits<double>::quiet_NaN();
}

/** A box-shaped prostate on an anisotropic grid (1 x 1.25 x 2.5 mm): along the axes through the centre of a face,
 * the signed distance to the face is exact, so the plan must follow its closed form at every voxel. */
bool
TestPlanProfile()
{
  bool                        ok = true;
  const std::array<double, 3> spacing{ { 1.0, 1.25, 2.5 } };
  const auto                  labels = MakeImage<LabelImage>({ { 120, 96, 48 } }, spacing, { { 0, 0, 0 } }, 1);
  // The prostate: voxel indices [40, 80) x [32, 64) x [16, 32): faces at (i - 1/2) h: x 39.5 / 79.5 mm,
  // z 38.75 / 78.75 mm; the profiles run along the centre lines through x = 59 mm, y = 60 mm, z = 57.5 mm.
  for (itk::ImageRegionIteratorWithIndex<LabelImage> it(labels, labels->GetLargestPossibleRegion()); !it.IsAtEnd();
       ++it)
  {
    const auto i = it.GetIndex();
    if (i[0] >= 40 && i[0] < 80 && i[1] >= 32 && i[1] < 64 && i[2] >= 16 && i[2] < 32)
    {
      it.Set(2);
    }
  }
  for (const double penumbra : { 6.0, 10.0 })
  {
    itk::ConformalPlanSettings plan;
    plan.marginMm = 5.0;
    plan.penumbraMm = penumbra;
    const double sigma = itk::PenumbraSigma(penumbra);
    const double Rx = plan.prescriptionGy;
    ok &= Near(sigma, penumbra / 1.6832424671458286, 1e-12, "sigma = width / (2 * 0.8416)");
    const auto dose = itk::MakeConformalDosePlan(labels, 2, plan);
    for (const int axis : { 0, 2 })
    {
      const double        h = spacing[axis];
      const double        face = axis == 0 ? 79.5 : 78.75; // the +x or +z face [mm]
      std::vector<double> positions, values;
      double              worst = 0.0;
      // From 10 mm inside the face (nearer to it than to any other face) to the grid's border.
      for (int k = axis == 0 ? 70 : 28; k < (axis == 0 ? 120 : 48); ++k)
      {
        LabelImage::IndexType index{ { 59, 48, 23 } }; // x 59, y 60, z 57.5 mm: >= 17.5 mm from the other faces
        index[axis] = k;
        const double x = k * h;
        const double expected = Rx * 0.5 * std::erfc((x - face - plan.marginMm) / (std::sqrt(2.0) * sigma));
        worst = std::max(worst, std::abs(dose->GetPixel(index) - expected));
        positions.push_back(x);
        values.push_back(dose->GetPixel(index));
      }
      const std::string where =
        (axis == 0 ? " along x (1 mm)" : " along z (2.5 mm)") + std::string(", penumbra ") + ToString(penumbra) + " mm";
      // The distance to a face along its normal is exact; the dose is stored as float (78 Gy: 1e-5 Gy) and the
      // distance map is float (1e-5 mm): 1e-3 Gy.
      ok &= Near(worst, 0.0, 1e-3, "plan = Rx erfc(d / sqrt(2) sigma) / 2 at every voxel" + where);
      // Rx/2 on the PTV surface (face + 5 mm), by linear interpolation between voxel centres: near the inflection
      // point the profile is nearly linear; |f''| h^2 / 8 over the slope Rx phi(0) / sigma bounds the error by
      // 0.01 mm at 1 mm and 0.07 mm at 2.5 mm.
      const double half = Crossing(positions, values, 0.5 * Rx);
      ok &= Near(half, face + plan.marginMm, axis == 0 ? 0.02 : 0.1, "Rx/2 on the PTV surface" + where);
      std::cout << "profile" << where << ": max |D - closed form| " << worst << " Gy, Rx/2 at " << half - face
                << " mm from the prostate's face";
      if (axis == 0)
      {
        // The 80-20 % width: each crossing by linear interpolation at 1 mm is off by at most
        // |f''| h^2 / 8 / slope = 0.03 mm (sigma 3.56 mm), so 0.1 mm on the width.
        const double width = Crossing(positions, values, 0.2 * Rx) - Crossing(positions, values, 0.8 * Rx);
        ok &= Near(width, penumbra, 0.1, "80-20 % width = the penumbra" + where);
        std::cout << ", 80-20 % width " << width << " mm";
      }
      std::cout << std::endl;
    }
  }
  // Inside the prostate, D >= Rx Phi(m / sigma) for every margin (its voxels are at least half a voxel deep).
  for (const double margin : { 0.0, 5.0, 2.0 * itk::PenumbraSigma(6.0), 13.0 })
  {
    itk::ConformalPlanSettings plan;
    plan.marginMm = margin;
    const auto                dose = itk::MakeConformalDosePlan(labels, 2, plan);
    const itk::DoseEvaluation e = itk::EvaluateDose(labels, dose, { { "prostate", 2 } });
    const double              bound = plan.prescriptionGy * NormalCdf(margin / itk::PenumbraSigma(6.0));
    ok &= Expect(e.Find("prostate").metrics.minimum >= bound - 1e-3,
                 "Dmin of the box prostate >= Rx Phi(m/sigma) = " + ToString(bound) + " Gy at margin " +
                   ToString(margin) + " mm: " + ToString(e.Find("prostate").metrics.minimum));
    if (margin >= 2.0 * itk::PenumbraSigma(6.0) - 1e-12)
    {
      ok &= Expect(e.Find("prostate").metrics.minimum >= 0.95 * plan.prescriptionGy,
                   "Dmin >= 0.95 Rx for a margin >= 2 sigma (" + ToString(margin) + " mm)");
    }
  }
  // A low-dose bath: unchanged deep inside, f Rx e^{-d/lambda} far outside (closed form, float storage: 1e-3 Gy).
  itk::ConformalPlanSettings bath;
  bath.bathFraction = 0.2;
  const auto   withBath = itk::MakeConformalDosePlan(labels, 2, bath);
  const double d = 119.0 - 79.5 - bath.marginMm; // voxel x = 119 on the +x centre line
  const double edge = 0.5 * std::erfc(d / (std::sqrt(2.0) * itk::PenumbraSigma(6.0)));
  ok &= Near(withBath->GetPixel({ { 119, 48, 23 } }),
             78.0 * (edge + 0.2 * (1.0 - edge) * std::exp(-d / 30.0)),
             1e-3,
             "low-dose bath far outside the PTV");
  ok &= Near(withBath->GetPixel({ { 59, 48, 23 } }), 78.0, 1e-3, "low-dose bath: Rx at the prostate's centre");
  return ok;
}

// ------------------------------------------------------------------ pelvis phantom: anterior rectal wall, margins

bool
TestPelvisPhantom()
{
  bool                         ok = true;
  bmr::PelvisPhantomParameters parameters; // 160 x 128 x 64 voxels of 1.25 x 1.25 x 2.5 mm
  const bmr::PhantomVolume     volume = bmr::MakePelvisPhantom(parameters);
  const auto                   labels = itk::MakeImageOnGrid<LabelImage>(volume.grid, volume.labels);
  const std::array<double, 3>  c = bmr::GridCenter(volume.grid);
  // The analytic rectum (bmrPhantom.cxx): a cylinder of radius 13 mm along z at x = c_x, y = c_y + 38 mm, up to
  // z = c_z + 15 mm, closed by a hemisphere; the prostate an ellipsoid centred at c + (0, 5, -15) mm.
  const double                axisY = c[1] + 38.0, topZ = c[2] + 15.0, radius = 13.0;
  const std::array<double, 3> prostateCentre{ { c[0], c[1] + 5.0, c[2] - 15.0 } };

  const auto  wall = itk::AnteriorRectalWallMask(labels, bmr::PelvisRectum, bmr::PelvisProstate);
  std::size_t wallVoxels = 0, outsideRectum = 0, tooDeep = 0, posteriorVoxels = 0;
  double      wallY = 0.0, rectumY = 0.0, wallToProstate = 0.0, posteriorToProstate = 0.0;
  std::size_t rectumVoxels = 0;
  for (itk::ImageRegionIteratorWithIndex<LabelImage> it(labels, labels->GetLargestPossibleRegion()); !it.IsAtEnd();
       ++it)
  {
    LabelImage::PointType x;
    labels->TransformIndexToPhysicalPoint(it.GetIndex(), x);
    const bool   inWall = wall->GetPixel(it.GetIndex()) != 0;
    const bool   inRectum = it.Get() == bmr::PelvisRectum;
    const double r = std::hypot(x[0] - c[0], x[1] - axisY);
    const double toProstate =
      std::hypot(std::hypot(x[0] - prostateCentre[0], x[1] - prostateCentre[1]), x[2] - prostateCentre[2]);
    if (inRectum)
    {
      ++rectumVoxels;
      rectumY += x[1];
    }
    if (inWall)
    {
      ++wallVoxels;
      outsideRectum += !inRectum;
      // In the cylinder part, depth below the analytic surface = 13 - r <= 3 mm, plus the staircase of the label
      // surface (at most half an in-plane voxel diagonal, 0.9 mm): r >= 9.1 mm.
      tooDeep += x[2] < topZ && r < radius - 3.0 - 0.9;
      wallY += x[1];
      wallToProstate += toProstate;
    }
    // The posterior shell: rectum voxels within 3 mm of the analytic surface, behind the rectum's axis.
    if (inRectum && x[2] < topZ && r >= radius - 3.0 && x[1] > axisY)
    {
      ++posteriorVoxels;
      posteriorToProstate += toProstate;
    }
  }
  ok &= Expect(wallVoxels > 100, "the anterior rectal wall of the phantom is not empty: " + ToString(wallVoxels));
  ok &= Expect(outsideRectum == 0,
               "the anterior rectal wall lies inside the rectum: " + ToString(outsideRectum) + " voxels outside");
  ok &= Expect(tooDeep == 0, "the anterior rectal wall is a 3 mm shell: " + ToString(tooDeep) + " voxels deeper");
  ok &= Expect(wallY / wallVoxels < axisY - 5.0 && wallY / wallVoxels < rectumY / rectumVoxels,
               "the anterior rectal wall lies anterior of the rectum's axis: mean y " + ToString(wallY / wallVoxels) +
                 " mm, axis " + ToString(axisY) + " mm");
  ok &=
    Expect(posteriorVoxels > 0 && wallToProstate / wallVoxels < posteriorToProstate / posteriorVoxels - 15.0,
           "the anterior rectal wall is closer to the prostate than the posterior wall: mean distance " +
             ToString(wallToProstate / wallVoxels) + " mm against " + ToString(posteriorToProstate / posteriorVoxels));

  // Margins 5 ... 13 mm: the prostate's D95 grows towards Rx, and the anterior rectal wall gets more dose.
  const bmr::Scene scene = bmr::PelvisPhantomScene(100.0, false);
  const auto       structures = itk::DoseStructuresFromScene(scene);
  ok &= Expect(structures.count("prostate") && structures.count("rectum") && !structures.count("air"),
               "the scene's structures: its labels but air");
  double       previousD95 = 0.0, previousWall = 0.0;
  const double sigma = itk::PenumbraSigma(6.0);
  std::cout << "margin_mm  prostate_D95_Gy  prostate_Dmin_Gy  prostate_gEUD_Gy  ARW_gEUD_Gy  ARW_V70Gy_pct\n";
  for (const double margin : { 5.0, 7.0, 9.0, 11.0, 13.0 })
  {
    itk::ConformalPlanSettings plan;
    plan.marginMm = margin;
    const auto                dose = itk::MakeConformalDosePlan(labels, bmr::PelvisProstate, plan);
    const itk::DoseEvaluation e = itk::EvaluateDose(labels, dose, structures);
    const auto &              prostate = e.Find("prostate").metrics;
    const auto &              arw = e.Find("anterior_rectal_wall").metrics;
    std::cout << margin << "  " << prostate.D95 << "  " << prostate.minimum << "  " << prostate.gEUD << "  " << arw.gEUD
              << "  " << 100.0 * arw.volumesAtDose[3].fraction << "\n";
    ok &= Expect(prostate.D95 > previousD95,
                 "prostate D95 increases with the margin: " + ToString(prostate.D95) + " Gy at " + ToString(margin) +
                   " mm");
    ok &= Expect(arw.gEUD > previousWall,
                 "anterior rectal wall gEUD increases with the margin: " + ToString(arw.gEUD) + " Gy at " +
                   ToString(margin) + " mm");
    // Every prostate voxel is at least half a voxel deep: D >= Rx Phi(m / sigma) (float: 1e-3 Gy).
    ok &= Expect(prostate.minimum >= 78.0 * NormalCdf(margin / sigma) - 1e-3,
                 "prostate Dmin >= Rx Phi(m/sigma) at " + ToString(margin) + " mm: " + ToString(prostate.minimum));
    ok &= Expect(prostate.D95 <= 78.0 + 1e-3 && prostate.gEUD <= prostate.mean, "D95 <= Rx, gEUD(a < 0) <= mean");
    previousD95 = prostate.D95;
    previousWall = arw.gEUD;
  }
  ok &= Expect(previousD95 >= 0.999 * 78.0, "prostate D95 within 0.1 % of Rx at 13 mm: " + ToString(previousD95));
  return ok;
}

// ------------------------------------------------------------------ other grids, warping, tables, errors

bool
TestResamplingAndWarping(const std::string & directory)
{
  bool ok = true;
  // A dose linear in x on a 3 mm grid that covers x in [0, 90] mm; labels on a 1 mm grid. Linear interpolation
  // of a linear function is exact: the resampled dose at x is 0.5 x (float: 1e-4 Gy).
  const auto dose = MakeImage<DoseImage>({ { 31, 20, 20 } }, { { 3, 3, 3 } }, { { 0, 0, 0 } }, 0.0f);
  Fill(dose.GetPointer(), [](const DoseImage::PointType & x) { return static_cast<float>(0.5 * x[0]); });
  // Organ 1: x voxel centres 10.5 ... 29.5 mm (mean 20 mm): Dmean 10 Gy; organ 2: 80.5 ... 99.5 mm, half of it
  // beyond the dose grid's last centre + half a voxel (91.5 mm): 8 of its 20 columns are outside.
  const auto labels = MakeImage<LabelImage>({ { 100, 10, 10 } }, { { 1, 1, 1 } }, { { 0.5, 10.5, 10.5 } }, 0);
  for (itk::ImageRegionIteratorWithIndex<LabelImage> it(labels, labels->GetLargestPossibleRegion()); !it.IsAtEnd();
       ++it)
  {
    const auto i = it.GetIndex()[0];
    it.Set(i >= 10 && i < 30 ? 1 : (i >= 80 ? 2 : 0));
  }
  const itk::DoseEvaluation e = itk::EvaluateDose(labels, dose, { { "near", 1 }, { "edge", 2 } });
  ok &= Expect(e.doseResampled, "a dose on another grid is resampled");
  ok &= Near(e.Find("near").metrics.mean, 10.0, 1e-4, "Dmean of a linear dose resampled onto the label grid");
  ok &= Near(e.Find("near").metrics.minimum, 5.25, 1e-4, "Dmin = 0.5 * 10.5 mm");
  ok &= Near(e.Find("near").fractionOutsideDoseGrid, 0.0, 0.0, "an organ inside the dose grid");
  ok &= Near(e.Find("edge").fractionOutsideDoseGrid,
             8.0 / 20.0,
             1e-15,
             "fraction of an organ beyond the dose grid (x > 91.5 mm: 92.5 ... 99.5)");

  // WarpDose: a uniform translation d = (3, 0, 0) mm gives out(x) = dose(x + 3) = 0.5 (x + 3) (1e-4 Gy).
  auto field = itk::DoseDisplacementFieldType::New();
  field->CopyInformation(labels);
  field->SetRegions(labels->GetLargestPossibleRegion());
  field->Allocate();
  itk::Vector<double, 3> shift;
  shift[0] = 3.0;
  shift[1] = 0.0;
  shift[2] = 0.0;
  field->FillBuffer(shift);
  const auto warped = itk::WarpDose(dose, field);
  ok &= Near(warped->GetPixel({ { 20, 5, 5 } }), 0.5 * (20.5 + 3.0), 1e-4, "warped dose = dose(x + d)");
  ok &= Near(warped->GetPixel({ { 99, 5, 5 } }), 0.0, 0.0, "warped dose outside the dose grid = 0 Gy");

  // The tables.
  const std::string dvh = itk::DoseVolumeHistogramCsv(e);
  const std::string metrics = itk::DoseMetricsCsv(e);
  ok &= Expect(dvh.rfind("dose_Gy,edge_cumulative_pct,near_cumulative_pct,edge_differential_pct,"
                         "near_differential_pct\n0,100,100,",
                         0) == 0,
               "dvh.csv header and first row:\n" + dvh.substr(0, 120));
  ok &= Expect(metrics.rfind("organ,a,gEUD_Gy,Dmean_Gy,D95_Gy,D2_Gy,D98_Gy,Dmin_Gy,Dmax_Gy,V50Gy_pct,V60Gy_pct,"
                             "V65Gy_pct,V70Gy_pct,V75Gy_pct,volume_cc,voxels,outside_dose_grid_pct\nedge,1,",
                             0) == 0,
               "dose_metrics.csv header:\n" + metrics.substr(0, 200));
  itk::WriteDoseEvaluation(directory, e);
  std::ifstream     in(directory + "/dose_metrics.csv");
  std::stringstream written;
  written << in.rdbuf();
  ok &= Expect(written.str() == metrics, "dose_metrics.csv as written");

  // The anterior rectal wall is skipped without both organs, and named structures must be present.
  ok &= Expect(e.structures.size() == 2, "no anterior rectal wall without rectum and prostate");
  return ok;
}

} // namespace

int
bmrDoseTest(int argc, char * argv[])
{
  if (argc < 2)
  {
    std::cerr << "usage: bmrDoseTest OUTPUT_DIRECTORY" << std::endl;
    return EXIT_FAILURE;
  }
  bool ok = TestEquivalentUniformDose();
  ok &= TestLinearDoseHistogram();
  ok &= TestPlanProfile();
  ok &= TestResamplingAndWarping(argv[1]);
  ok &= TestPelvisPhantom();

  // Refused inputs.
  ITK_TRY_EXPECT_EXCEPTION(bmr::GeneralizedEquivalentUniformDose({}, 1.0));
  ITK_TRY_EXPECT_EXCEPTION(bmr::GeneralizedEquivalentUniformDose({ 1.0, -0.5 }, 1.0));
  ITK_TRY_EXPECT_EXCEPTION(bmr::GeneralizedEquivalentUniformDose({ 1.0 }, std::nan("")));
  ITK_TRY_EXPECT_EXCEPTION(bmr::ComputeDoseVolumeHistogram({ 1.0 }, 1.0, 0.0));
  ITK_TRY_EXPECT_EXCEPTION(bmr::DoseAtVolume({ 1.0 }, 101.0));
  const auto labels = MakeImage<LabelImage>({ { 10, 10, 10 } }, { { 1, 1, 1 } }, { { 0, 0, 0 } }, 1);
  auto       dose = MakeImage<DoseImage>({ { 10, 10, 10 } }, { { 1, 1, 1 } }, { { 0, 0, 0 } }, 1.0f);
  ITK_TRY_EXPECT_EXCEPTION(itk::EvaluateDose(labels, dose, { { "prostate", 2 } }));
  ITK_TRY_EXPECT_EXCEPTION(itk::MakeConformalDosePlan(labels, 2));
  itk::ConformalPlanSettings negative;
  negative.marginMm = -1.0;
  ITK_TRY_EXPECT_EXCEPTION(itk::MakeConformalDosePlan(labels, 1, negative));
  ITK_TRY_EXPECT_EXCEPTION(itk::AnteriorRectalWallMask(labels, 4, 2));
  dose->SetPixel({ { 3, 3, 3 } }, -1.0f);
  ITK_TRY_EXPECT_EXCEPTION(itk::EvaluateDose(labels, dose, { { "tissue", 1 } }));

  std::cout << (ok ? "bmrDoseTest passed" : "bmrDoseTest FAILED") << std::endl;
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}
