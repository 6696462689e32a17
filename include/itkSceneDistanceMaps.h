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
#ifndef itkSceneDistanceMaps_h
#define itkSceneDistanceMaps_h

#include "bmrScene.h"
#include "itkSliceInterpolation.h"
#include "itkBinaryThresholdImageFilter.h"
#include "itkImageRegionConstIterator.h"
#include "itkRegionOfInterestImageFilter.h"
#include "itkIsoContourDistanceImageFilter.h"
#include "itkSignedMaurerDistanceMapImageFilter.h"

#include <algorithm>
#include <cmath>

#include <map>
#include <string>

namespace itk {

namespace detail {
/** Maurer's signed map [mm, negative inside] of the mask of \a image's voxels in [lower, upper] and of its
 * complement, averaged: \f$ \phi = (\phi_{mask} - \phi_{complement}) / 2 \f$, over the whole of \a image. */
template<typename TImage>
typename Image<float, 3>::Pointer
MaskAndComplementMap(const TImage * image, typename TImage::PixelType lower, typename TImage::PixelType upper)
{
  using MapType = Image<float, 3>;
  using MaskType = Image<unsigned char, 3>;
  typename MapType::Pointer part[2];
  for (int complement = 0; complement < 2; ++complement)
  {
    auto threshold = BinaryThresholdImageFilter<TImage, MaskType>::New();
    threshold->SetInput(image);
    threshold->SetLowerThreshold(lower);
    threshold->SetUpperThreshold(upper);
    threshold->SetInsideValue(complement ? 0 : 1);
    threshold->SetOutsideValue(complement ? 1 : 0);
    auto distance = SignedMaurerDistanceMapImageFilter<MaskType, MapType>::New();
    distance->SetInput(threshold->GetOutput());
    distance->SetUseImageSpacing(true);
    distance->SetSquaredDistance(false);
    distance->SetInsideIsPositive(false);
    distance->SetBackgroundValue(0);
    distance->Update();
    part[complement] = distance->GetOutput();
    part[complement]->DisconnectPipeline();
  }
  float *           organ = part[0]->GetBufferPointer();
  const float *     rest = part[1]->GetBufferPointer();
  const std::size_t n = part[0]->GetBufferedRegion().GetNumberOfPixels();
  for (std::size_t i = 0; i < n; ++i)
  {
    organ[i] = 0.5f * (organ[i] - rest[i]);
  }
  return part[0];
}

/** The index box of \a image's voxels in [lower, upper], grown by \a marginMM on every side and clipped to the
 * image; an empty region when no voxel lies in [lower, upper]. */
template<typename TImage>
ImageRegion<3>
PaddedMaskBox(const TImage * image, typename TImage::PixelType lower, typename TImage::PixelType upper, double marginMM)
{
  const ImageRegion<3> whole = image->GetLargestPossibleRegion();
  const auto *         value = image->GetBufferPointer();
  IndexValueType       lo[3], hi[3];
  for (unsigned int a = 0; a < 3; ++a)
  {
    lo[a] = static_cast<IndexValueType>(whole.GetSize(a));
    hi[a] = -1;
  }
  IndexValueType i[3];
  for (i[2] = 0; i[2] < static_cast<IndexValueType>(whole.GetSize(2)); ++i[2])
  {
    for (i[1] = 0; i[1] < static_cast<IndexValueType>(whole.GetSize(1)); ++i[1])
    {
      for (i[0] = 0; i[0] < static_cast<IndexValueType>(whole.GetSize(0)); ++i[0], ++value)
      {
        if (*value >= lower && *value <= upper)
        {
          for (unsigned int a = 0; a < 3; ++a)
          {
            lo[a] = std::min(lo[a], i[a]);
            hi[a] = std::max(hi[a], i[a]);
          }
        }
      }
    }
  }
  ImageRegion<3> box;
  if (hi[0] < 0)
  {
    return box;
  }
  for (unsigned int a = 0; a < 3; ++a)
  {
    const auto pad = static_cast<IndexValueType>(std::ceil(marginMM / image->GetSpacing()[a]));
    const auto first = std::max<IndexValueType>(lo[a] - pad, 0);
    const auto last = std::min<IndexValueType>(hi[a] + pad, static_cast<IndexValueType>(whole.GetSize(a)) - 1);
    box.SetIndex(a, whole.GetIndex(a) + first);
    box.SetSize(a, static_cast<SizeValueType>(last - first + 1));
  }
  return box;
}

/** \a boxMap (the map on \a box, x fastest) on the whole grid of \a image: inside the box its values; outside,
 * \f$ \phi(y) + |x - y| \f$ with y the box voxel nearest to x, an upper bound of the distance that is continuous
 * and grows with slope 1 away from the box. */
template<typename TImage>
typename Image<float, 3>::Pointer
ExtendBeyondBox(const float * boxMap, const ImageRegion<3> & box, const TImage * image)
{
  using MapType = Image<float, 3>;
  const ImageRegion<3> whole = image->GetLargestPossibleRegion();
  auto                 out = MapType::New();
  out->CopyInformation(image);
  out->SetRegions(whole);
  out->Allocate();
  float *        value = out->GetBufferPointer();
  IndexValueType first[3], last[3], size[3];
  for (unsigned int a = 0; a < 3; ++a)
  {
    first[a] = box.GetIndex(a) - whole.GetIndex(a);
    last[a] = first[a] + static_cast<IndexValueType>(box.GetSize(a)) - 1;
    size[a] = static_cast<IndexValueType>(whole.GetSize(a));
  }
  const auto & spacing = image->GetSpacing();
  // The squared distance along one axis from index i to the box's nearest index there, and that index.
  const auto gap = [&](unsigned int a, IndexValueType i, IndexValueType & nearest) {
    nearest = std::min(std::max(i, first[a]), last[a]);
    const double d = static_cast<double>(i - nearest) * spacing[a];
    return d * d;
  };
  IndexValueType i[3], y[3];
  for (i[2] = 0; i[2] < size[2]; ++i[2])
  {
    const double gz = gap(2, i[2], y[2]);
    for (i[1] = 0; i[1] < size[1]; ++i[1])
    {
      const double gyz = gz + gap(1, i[1], y[1]);
      for (i[0] = 0; i[0] < size[0]; ++i[0], ++value)
      {
        const double      squared = gyz + gap(0, i[0], y[0]);
        const std::size_t inBox =
          static_cast<std::size_t>(y[0] - first[0]) +
          static_cast<std::size_t>(box.GetSize(0)) *
            (static_cast<std::size_t>(y[1] - first[1]) +
             static_cast<std::size_t>(box.GetSize(1)) * static_cast<std::size_t>(y[2] - first[2]));
        *value = boxMap[inBox] + static_cast<float>(std::sqrt(squared));
      }
    }
  }
  return out;
}

/** The signed distance [mm, negative inside] to the voxel faces of the mask of \a image's voxels in [lower, upper]
 * (MaskAndComplementMap()). With a finite \a exactWithinMM the maps are computed on the mask's box grown by that
 * margin only, which holds every voxel within the margin and every contour voxel of the mask and of its
 * complement nearest to one (Maurer's contours do not include the image's border): equal to the whole image's
 * map within \a exactWithinMM of the mask, to float rounding, and beyond it the upper bound of ExtendBeyondBox().
 * An organ fills a small part of a pelvis scan, so this costs a fraction of the whole image's maps. */
template<typename TImage>
typename Image<float, 3>::Pointer
FaceDistanceMap(const TImage *             image,
                typename TImage::PixelType lower,
                typename TImage::PixelType upper,
                double                     exactWithinMM = NumericTraits<double>::infinity())
{
  const ImageRegion<3> whole = image->GetLargestPossibleRegion();
  if (!std::isfinite(exactWithinMM) || image->GetBufferedRegion() != whole)
  {
    return MaskAndComplementMap(image, lower, upper);
  }
  const ImageRegion<3> box = PaddedMaskBox(image, lower, upper, exactWithinMM);
  if (box.GetNumberOfPixels() == 0 || 2 * box.GetNumberOfPixels() > whole.GetNumberOfPixels())
  {
    return MaskAndComplementMap(image, lower, upper); // no mask, or the box saves little
  }
  auto crop = RegionOfInterestImageFilter<TImage, TImage>::New();
  crop->SetInput(image);
  crop->SetRegionOfInterest(box);
  crop->Update();
  const auto boxMap = MaskAndComplementMap(crop->GetOutput(), lower, upper);
  return ExtendBeyondBox(boxMap->GetBufferPointer(), box, image);
}
/** FaceDistanceMap() of the mask of \a image's voxels in [lower, upper] after shape-based interpolation between
 * its thick slices (InterpolateLabelSlices()): on the mask's box grown by \a exactWithinMM (the whole image when
 * infinite), refined along the slice axis. The map is defined on that box only; beyond it a sampler holds the
 * border's value, which is farther from the organ than the objective's surfaces reach. */
template<typename TImage>
typename Image<float, 3>::Pointer
SliceInterpolatedFaceMap(const TImage *             image,
                         typename TImage::PixelType lower,
                         typename TImage::PixelType upper,
                         double                     exactWithinMM)
{
  using MaskType = Image<unsigned char, 3>;
  const ImageRegion<3> box = std::isfinite(exactWithinMM) ? PaddedMaskBox(image, lower, upper, exactWithinMM)
                                                          : image->GetLargestPossibleRegion();
  auto                 crop = RegionOfInterestImageFilter<TImage, TImage>::New();
  crop->SetInput(image);
  crop->SetRegionOfInterest(box);
  auto mask = BinaryThresholdImageFilter<TImage, MaskType>::New();
  mask->SetInput(crop->GetOutput());
  mask->SetLowerThreshold(lower);
  mask->SetUpperThreshold(upper);
  mask->SetInsideValue(1);
  mask->SetOutsideValue(0);
  mask->Update();
  const typename MaskType::ConstPointer refined = InterpolateLabelSlices(mask->GetOutput());
  return MaskAndComplementMap(refined.GetPointer(), 1, 1);
}
} // namespace detail

/** How far from an organ [mm] ComputeSceneDistanceMaps() computes its distance exactly by default: beyond the
 * 25 mm bladder fillings the benchmarks simulate, where the objective samples the map. */
constexpr double SceneDistanceExactWithinMM = 30.0;

/** \brief Signed distance maps [mm] of the scene's objective organs in a fixed label image.
 *
 * For every objective label of \a scene, the signed Euclidean distance to the
 * organ's surface is computed with itk::SignedMaurerDistanceMapImageFilter in
 * physical units (image spacing used, negative inside). Maurer's map is zero on
 * the organ's own boundary voxels, half a voxel inside the label surface that
 * the mesher meshes (the faces between organ and background voxels); the
 * average of the map of the organ and the negated map of its complement,
 * \f$ \phi = (\phi_{organ} - \phi_{complement}) / 2 \f$, is zero on those
 * faces and equals the distance to them along the grid axes.
 * These are the inputs FEMElasticityOptimizer::SetDistanceMap() expects; a user
 * with their own maps (for example from a surface mesh) passes those instead.
 * Only the objective labels are computed: nothing the scene does not use, and
 * each on its organ's neighbourhood only: the map is exact within
 * \a exactWithinMM of the organ (the default, SceneDistanceExactWithinMM, is
 * farther than an organ surface moves between two scans) and beyond it an upper
 * bound of the distance (detail::FaceDistanceMap()); infinity computes every
 * voxel exactly.
 *
 * Thick slices (ThickSlices(): 2-3 mm slices of a 1 mm in-plane CT): with \a interpolateSlices each
 * organ's mask is first interpolated between its slices (InterpolateLabelSlices()) and the map is that of the
 * interpolated mask, on the organ's box grown by \a exactWithinMM and refined along the slice axis
 * (detail::SliceInterpolatedFaceMap()); the slice-thick terraces of the voxel faces would otherwise be read as
 * surface motion of up to a slice. Without thick slices the maps are those above, whatever \a interpolateSlices.
 *
 * Throws itk::ExceptionObject naming the label when an objective label does not
 * occur in \a labels, and when the image is empty.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationScene
 */
template<typename TLabelImage>
std::map<std::string, typename Image<float, 3>::Pointer>
ComputeSceneDistanceMaps(const TLabelImage * labels,
                         const bmr::Scene &  scene,
                         double              exactWithinMM = SceneDistanceExactWithinMM,
                         bool                interpolateSlices = false)
{
  using MapType = Image<float, 3>;
  if (labels == nullptr || labels->GetLargestPossibleRegion().GetNumberOfPixels() == 0)
  {
    itkGenericExceptionMacro(<< "ComputeSceneDistanceMaps: the fixed label image is empty");
  }
  std::map<std::string, typename MapType::Pointer> maps;
  for (const bmr::ObjectiveTerm & term : scene.objective)
  {
    const bmr::SceneLabel * label = scene.FindLabel(term.label);
    if (label == nullptr)
    {
      itkGenericExceptionMacro(<< "ComputeSceneDistanceMaps: objective label \"" << term.label
                               << "\" is not defined in the scene");
    }
    std::size_t count = 0;
    for (ImageRegionConstIterator<TLabelImage> it(labels, labels->GetLargestPossibleRegion()); !it.IsAtEnd(); ++it)
    {
      count += static_cast<std::int64_t>(it.Get()) == label->value;
    }
    if (count == 0)
    {
      itkGenericExceptionMacro(<< "objective label \"" << term.label << "\" (value " << label->value
                               << ") is missing from the fixed label image");
    }
    const auto value = static_cast<typename TLabelImage::PixelType>(label->value);
    maps[term.label] = interpolateSlices && ThickSlices(labels).axis >= 0
                         ? detail::SliceInterpolatedFaceMap(labels, value, value, exactWithinMM)
                         : detail::FaceDistanceMap(labels, value, value, exactWithinMM);
  }
  return maps;
}

/** \brief Signed distance map [mm, negative inside] of the 0.5 level of a probability or partial-volume image.
 *
 * \a probability holds, per voxel, the organ's probability (a segmentation network's softmax) or its volume
 * fraction, in [0, 1]. The surface is the 0.5 level of its trilinear interpolation, a sub-voxel surface where a
 * label map has a staircase. Near it (the voxels whose 6-neighborhood crosses the level)
 * itk::IsoContourDistanceImageFilter gives the distance to the linearly interpolated level in physical units;
 * farther away, the Euclidean distance to the faces of the mask p >= 0.5 (SignedMaurerDistanceMapImageFilter of
 * the mask and of its complement, averaged, as ComputeSceneDistanceMaps), which differs from the sub-voxel
 * distance by less than half a voxel where the band ends. Throws itk::ExceptionObject naming \a what when a voxel
 * is not finite or lies outside [0, 1] (beyond 1e-3), or when no voxel reaches 0.5.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationScene */
template<typename TProbabilityImage>
typename Image<float, 3>::Pointer
ComputeProbabilityDistanceMap(const TProbabilityImage * probability, const std::string & what)
{
  using MapType = Image<float, 3>;
  if (probability == nullptr || probability->GetLargestPossibleRegion().GetNumberOfPixels() == 0)
  {
    itkGenericExceptionMacro(<< what << ": the probability image is empty");
  }
  std::size_t inside = 0;
  for (ImageRegionConstIterator<TProbabilityImage> it(probability, probability->GetLargestPossibleRegion());
       !it.IsAtEnd();
       ++it)
  {
    const double p = static_cast<double>(it.Get());
    if (!std::isfinite(p) || p < -1e-3 || p > 1.0 + 1e-3)
    {
      itkGenericExceptionMacro(<< what << ": a voxel holds " << p << ", not a probability in [0, 1]");
    }
    inside += p >= 0.5;
  }
  if (inside == 0)
  {
    itkGenericExceptionMacro(<< what << ": no voxel reaches 0.5, the organ is absent");
  }
  // Far from the surface: the mask's distance map, as ComputeSceneDistanceMaps does for a label.
  const auto phiMap = detail::FaceDistanceMap(probability,
                                              static_cast<typename TProbabilityImage::PixelType>(0.5),
                                              NumericTraits<typename TProbabilityImage::PixelType>::max());
  // Near it: the distance to the interpolated 0.5 level (positive where p > 0.5, hence the sign flip).
  auto       iso = IsoContourDistanceImageFilter<TProbabilityImage, MapType>::New();
  const auto far = NumericTraits<float>::max();
  iso->SetInput(probability);
  iso->SetLevelSetValue(0.5);
  iso->SetFarValue(far);
  iso->Update();
  float *           phi = phiMap->GetBufferPointer();
  const float *     near = iso->GetOutput()->GetBufferPointer();
  const std::size_t n = phiMap->GetBufferedRegion().GetNumberOfPixels();
  for (std::size_t i = 0; i < n; ++i)
  {
    phi[i] = std::abs(near[i]) < far ? -near[i] : phi[i];
  }
  return phiMap;
}

} // namespace itk

#endif
