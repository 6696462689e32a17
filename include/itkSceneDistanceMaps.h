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
#include "itkBinaryThresholdImageFilter.h"
#include "itkImageRegionConstIterator.h"
#include "itkIsoContourDistanceImageFilter.h"
#include "itkSignedMaurerDistanceMapImageFilter.h"

#include <cmath>

#include <map>
#include <string>

namespace itk {

namespace detail {
/** The signed distance [mm, negative inside] to the voxel faces of the mask of \a image's voxels in [lower, upper]:
 * Maurer's map of the mask and of its complement, averaged, \f$ \phi = (\phi_{mask} - \phi_{complement}) / 2 \f$. */
template<typename TImage>
typename Image<float, 3>::Pointer
FaceDistanceMap(const TImage * image, typename TImage::PixelType lower, typename TImage::PixelType upper)
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
} // namespace detail

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
 * Only the objective labels are computed: nothing the scene does not use.
 *
 * Throws itk::ExceptionObject naming the label when an objective label does not
 * occur in \a labels, and when the image is empty.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationScene
 */
template<typename TLabelImage>
std::map<std::string, typename Image<float, 3>::Pointer>
ComputeSceneDistanceMaps(const TLabelImage * labels, const bmr::Scene & scene)
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
    maps[term.label] = detail::FaceDistanceMap(labels, value, value);
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
