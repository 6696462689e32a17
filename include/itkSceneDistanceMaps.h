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
#include "itkSignedMaurerDistanceMapImageFilter.h"

#include <map>
#include <string>

namespace itk {

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
  using MaskType = Image<unsigned char, 3>;
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
    // Signed map of the organ (inside = 1) and of its complement (inside = 0).
    typename MapType::Pointer part[2];
    for (int complement = 0; complement < 2; ++complement)
    {
      using ThresholdType = BinaryThresholdImageFilter<TLabelImage, MaskType>;
      auto threshold = ThresholdType::New();
      threshold->SetInput(labels);
      threshold->SetLowerThreshold(static_cast<typename TLabelImage::PixelType>(label->value));
      threshold->SetUpperThreshold(static_cast<typename TLabelImage::PixelType>(label->value));
      threshold->SetInsideValue(complement ? 0 : 1);
      threshold->SetOutsideValue(complement ? 1 : 0);
      using DistanceType = SignedMaurerDistanceMapImageFilter<MaskType, MapType>;
      auto distance = DistanceType::New();
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
    maps[term.label] = part[0];
  }
  return maps;
}

} // namespace itk

#endif
