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
#ifndef itkRegistrationQualityMeasures_h
#define itkRegistrationQualityMeasures_h

#include "bmrStatistics.h"
#include "itkBinaryThresholdImageFilter.h"
#include "itkDisplacementFieldJacobianDeterminantFilter.h"
#include "itkLabelOverlapMeasuresImageFilter.h"
#include "itkImageRegionConstIterator.h"
#include "itkImageRegionConstIteratorWithIndex.h"
#include "itkSignedMaurerDistanceMapImageFilter.h"

#include <cmath>
#include <limits>
#include <map>
#include <vector>

namespace itk {

/** Voxel counts of one label in two label maps on one grid, and their Dice coefficient
 * 2|A ∩ B| / (|A| + |B|) (0 when both are empty; check the counts). */
struct LabelOverlap
{
  std::size_t inA{ 0 };
  std::size_t inB{ 0 };
  std::size_t inBoth{ 0 };
  double      dice{ 0.0 };
};

/** Overlap of every label of \a a and \a b (same grid; throws otherwise), counted in one pass by ITK's
 * LabelOverlapMeasuresImageFilter (a = source, b = target); a label absent from both has no entry.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationEvaluation */
template<typename TLabelImage>
std::map<typename TLabelImage::PixelType, LabelOverlap>
ComputeLabelOverlaps(const TLabelImage * a, const TLabelImage * b)
{
  if (a->GetLargestPossibleRegion() != b->GetLargestPossibleRegion())
  {
    itkGenericExceptionMacro(<< "ComputeLabelOverlap: the two label images differ in size");
  }
  auto overlap = LabelOverlapMeasuresImageFilter<TLabelImage>::New();
  overlap->SetSourceImage(a);
  overlap->SetTargetImage(b);
  overlap->Update();
  std::map<typename TLabelImage::PixelType, LabelOverlap> overlaps;
  for (const auto & kv : overlap->GetLabelSetMeasures())
  {
    LabelOverlap & o = overlaps[kv.first];
    o.inA = kv.second.m_Source;
    o.inB = kv.second.m_Target;
    o.inBoth = kv.second.m_Intersection;
    o.dice = o.inA + o.inB > 0 ? 2.0 * double(o.inBoth) / double(o.inA + o.inB) : 0.0;
  }
  return overlaps;
}

/** Overlap of one \a label in \a a and \a b (ComputeLabelOverlaps(); zero counts when absent from both).
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationEvaluation */
template<typename TLabelImage>
LabelOverlap
ComputeLabelOverlap(const TLabelImage * a, const TLabelImage * b, typename TLabelImage::PixelType label)
{
  const auto overlaps = ComputeLabelOverlaps(a, b);
  const auto found = overlaps.find(label);
  return found == overlaps.end() ? LabelOverlap() : found->second;
}

/** Symmetric surface distances [mm] between one label in two label maps: mean, 95th percentile ("HD95")
 * and maximum (Hausdorff distance). */
struct SurfaceDistanceStatistics
{
  double mean{ 0.0 };
  double percentile95{ 0.0 };
  double maximum{ 0.0 };
};

/** \brief Symmetric surface distances [mm] between \a label in \a a and in \a b.
 *
 * The surface of a label is the set of its voxels with a 6-neighbor outside it. For each surface voxel of
 * A, the distance to the surface of B is read from B's signed Maurer distance map (physical spacing); the
 * same from B to A. Of the pooled distances the result gives the mean, the 95th percentile (linear
 * interpolation) — the "HD95" of segmentation papers, robust to a few outlying voxels — and the maximum.
 * Throws when the label is absent from either image or the grids differ.
 * Not ITK's HausdorffDistanceImageFilter: it gives the maximum and the mean distance over every voxel of each
 * object (interior voxels included, at distance 0 inside the other), not the distances of the surfaces, and
 * no percentile; HD95 needs the pooled surface distances.
 * \ingroup BiomechanicalRegistrationEvaluation
 */
template<typename TLabelImage>
SurfaceDistanceStatistics
ComputeSurfaceDistances(const TLabelImage * a, const TLabelImage * b, typename TLabelImage::PixelType label)
{
  constexpr unsigned int Dimension = TLabelImage::ImageDimension;
  using MaskType = Image<unsigned char, Dimension>;
  using MapType = Image<float, Dimension>;
  if (a->GetLargestPossibleRegion() != b->GetLargestPossibleRegion())
  {
    itkGenericExceptionMacro(<< "ComputeSurfaceDistances: the two label images differ in size");
  }
  const auto mapOf = [label](const TLabelImage * image) {
    auto threshold = BinaryThresholdImageFilter<TLabelImage, MaskType>::New();
    threshold->SetInput(image);
    threshold->SetLowerThreshold(label);
    threshold->SetUpperThreshold(label);
    threshold->SetInsideValue(1);
    threshold->SetOutsideValue(0);
    auto maurer = SignedMaurerDistanceMapImageFilter<MaskType, MapType>::New();
    maurer->SetInput(threshold->GetOutput());
    maurer->SetUseImageSpacing(true);
    maurer->SetSquaredDistance(false);
    maurer->SetInsideIsPositive(false);
    maurer->Update();
    return typename MapType::Pointer(maurer->GetOutput());
  };
  std::vector<double> distances;
  const TLabelImage * images[2] = { a, b };
  for (int k = 0; k < 2; ++k)
  {
    const TLabelImage *             self = images[k];
    const typename MapType::Pointer other = mapOf(images[1 - k]);
    const auto                      region = self->GetLargestPossibleRegion();
    std::size_t                     found = 0;
    for (ImageRegionConstIteratorWithIndex<TLabelImage> it(self, region); !it.IsAtEnd(); ++it)
    {
      if (it.Get() != label)
      {
        continue;
      }
      ++found;
      bool surface = false;
      for (unsigned int axis = 0; axis < Dimension && !surface; ++axis)
      {
        for (int step = -1; step <= 1 && !surface; step += 2)
        {
          auto n = it.GetIndex();
          n[axis] += step;
          surface = !region.IsInside(n) || self->GetPixel(n) != label;
        }
      }
      if (surface)
      {
        distances.push_back(std::abs(double(other->GetPixel(it.GetIndex()))));
      }
    }
    if (found == 0)
    {
      itkGenericExceptionMacro(<< "ComputeSurfaceDistances: label " << static_cast<double>(label)
                               << " does not occur in " << (k == 0 ? "the first" : "the second") << " image");
    }
  }
  const bmr::SummaryStatistics summary = bmr::Summarize(distances);
  SurfaceDistanceStatistics    result;
  result.mean = summary.mean;
  result.percentile95 = bmr::Percentile(distances, 95.0);
  result.maximum = summary.maximum;
  return result;
}

/** Statistics of the Jacobian determinant J of x -> x + d(x) over a field's voxels (all but the outermost
 * layer, where only one-sided differences exist): minimum, fraction of
 * voxels with J <= 0 (folded), and the standard deviation of log J over the voxels with J > 0
 * (0 for a rigid or volume-preserving map; larger for rougher fields). */
struct JacobianDeterminantStatistics
{
  double minimum{ 0.0 };
  double fractionNonPositive{ 0.0 };
  double standardDeviationOfLog{ 0.0 };
};

/** Jacobian determinant statistics of \a field (physical spacing, central differences).
 * \ingroup BiomechanicalRegistration */
template<typename TDisplacementField>
JacobianDeterminantStatistics
ComputeJacobianDeterminantStatistics(const TDisplacementField * field)
{
  using JacobianFilter = DisplacementFieldJacobianDeterminantFilter<TDisplacementField, float>;
  auto jacobian = JacobianFilter::New();
  jacobian->SetInput(field);
  jacobian->SetUseImageSpacingOn();
  jacobian->Update();
  // The outermost voxel layer is left out: the filter's one-sided boundary differences are not derivatives.
  auto region = field->GetLargestPossibleRegion();
  for (unsigned int a = 0; a < TDisplacementField::ImageDimension; ++a)
  {
    if (region.GetSize(a) > 2)
    {
      region.SetIndex(a, region.GetIndex(a) + 1);
      region.SetSize(a, region.GetSize(a) - 2);
    }
  }
  JacobianDeterminantStatistics s;
  s.minimum = std::numeric_limits<double>::max();
  std::size_t nonPositive = 0, positive = 0, n = 0;
  double      sum = 0.0, squares = 0.0;
  for (ImageRegionConstIterator<typename JacobianFilter::OutputImageType> it(jacobian->GetOutput(), region);
       !it.IsAtEnd();
       ++it, ++n)
  {
    const double J = it.Get();
    s.minimum = std::min(s.minimum, J);
    if (J <= 0.0)
    {
      ++nonPositive;
      continue;
    }
    const double l = std::log(J);
    sum += l;
    squares += l * l;
    ++positive;
  }
  s.fractionNonPositive = double(nonPositive) / double(n);
  if (positive > 1)
  {
    const double mean = sum / double(positive);
    s.standardDeviationOfLog =
      std::sqrt(std::max(0.0, (squares - double(positive) * mean * mean) / double(positive - 1)));
  }
  return s;
}

} // namespace itk

#endif
