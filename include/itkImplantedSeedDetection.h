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
#ifndef itkImplantedSeedDetection_h
#define itkImplantedSeedDetection_h

#include "bmrLandmarks.h"
#include "itkConnectedComponentImageFilter.h"
#include "itkImageRegionConstIteratorWithIndex.h"
#include "itkImageRegionIterator.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace itk {

/** Parameters of DetectImplantedSeeds(). Intensities in HU, volumes in mm³. */
struct ImplantedSeedDetectionParameters
{
  double thresholdHU{ 1000.0 };    ///< a seed has at least one voxel above this (soft tissue ~40 HU)
  double growThresholdHU{ 400.0 }; ///< a seed is the connected region above this around such voxels
  double minimumVolume{ 0.5 };     ///< candidates with less volume above growThresholdHU are noise
  double maximumVolume{ 200.0 };   ///< larger bright blobs are not seeds (a 1.5 x 8 mm seed is 14 mm³)
};

/** \brief Finds bright implanted seeds (fiducial markers) inside an organ and returns their centroids
 * (LPS mm) as landmarks "seed0", "seed1", ... in the raster order of their first voxel.
 *
 * A seed is a 26-connected component of voxels brighter than growThresholdHU that holds a voxel brighter
 * than thresholdHU, touches the organ's label and whose volume lies in [minimumVolume, maximumVolume]
 * (two thresholds, as in hysteresis thresholding: a thin tilted seed's partial-volume voxels fall below
 * the high one and would split it). Its position is the
 * intensity-weighted centroid
 * \f[ c = \frac{\sum_v w_v x_v}{\sum_v w_v}, \qquad w_v = \max(0, I_v - b) , \f]
 * over the component and the voxels next to it (26-neighbors not in another component), with b the
 * organ's mean intensity below growThresholdHU. Weighting by the excess intensity over a one-voxel ring
 * counts the partial-volume voxels at the seed's surface, so the centroid is not quantized to the grid
 * (sub-voxel accuracy; 0.5 mm or better at 1.25 x 1.25 x 2.5 mm voxels on the phantom, see the test).
 *
 * \a labels must share \a ct's grid. Throws itk::ExceptionObject when the grids differ or the organ is
 * absent. Use bmr::MatchLandmarks() to pair the seeds found in two scans.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationEvaluation
 */
template<typename TImage, typename TLabelImage>
std::vector<bmr::Landmark>
DetectImplantedSeeds(const TImage *                           ct,
                     const TLabelImage *                      labels,
                     typename TLabelImage::PixelType          organ,
                     const ImplantedSeedDetectionParameters & parameters = ImplantedSeedDetectionParameters())
{
  constexpr unsigned int Dimension = TImage::ImageDimension;
  using ComponentImageType = Image<std::uint32_t, Dimension>;
  using MaskType = Image<unsigned char, Dimension>;
  const auto region = ct->GetLargestPossibleRegion();
  if (!(parameters.growThresholdHU <= parameters.thresholdHU) ||
      !(parameters.minimumVolume <= parameters.maximumVolume))
  {
    itkGenericExceptionMacro(<< "DetectImplantedSeeds: needs growThresholdHU <= thresholdHU and minimumVolume <= "
                                "maximumVolume");
  }
  if (labels->GetLargestPossibleRegion() != region ||
      !labels->GetOrigin().GetVnlVector().is_equal(ct->GetOrigin().GetVnlVector(), 1e-6) ||
      !labels->GetSpacing().GetVnlVector().is_equal(ct->GetSpacing().GetVnlVector(), 1e-9))
  {
    itkGenericExceptionMacro(<< "DetectImplantedSeeds: the label image does not share the CT's grid");
  }

  // Mean organ intensity below the threshold: the background the seed's excess intensity is measured from.
  auto mask = MaskType::New();
  mask->CopyInformation(ct);
  mask->SetRegions(region);
  mask->Allocate(true);
  double      background = 0.0;
  std::size_t organVoxels = 0;
  {
    ImageRegionConstIterator<TImage>      it(ct, region);
    ImageRegionConstIterator<TLabelImage> lt(labels, region);
    ImageRegionIterator<MaskType>         mt(mask, region);
    for (; !it.IsAtEnd(); ++it, ++lt, ++mt)
    {
      const double v = static_cast<double>(it.Get());
      mt.Set(v > parameters.growThresholdHU ? 1 : 0);
      if (lt.Get() == organ && v <= parameters.growThresholdHU)
      {
        background += v;
        ++organVoxels;
      }
    }
  }
  if (organVoxels == 0)
  {
    itkGenericExceptionMacro(<< "DetectImplantedSeeds: organ label " << static_cast<double>(organ)
                             << " does not occur in the label image");
  }
  background /= double(organVoxels);

  using ComponentsType = ConnectedComponentImageFilter<MaskType, ComponentImageType>;
  auto components = ComponentsType::New();
  components->SetInput(mask);
  components->FullyConnectedOn();
  components->Update();
  const ComponentImageType * cc = components->GetOutput();
  const std::size_t          count = components->GetObjectCount();

  // Bounding box, thresholded size and organ contact of every component.
  std::vector<typename ComponentImageType::IndexType> lower(count + 1), upper(count + 1);
  std::vector<std::size_t>                            size(count + 1, 0);
  std::vector<bool>                                   touches(count + 1, false);
  std::vector<double>                                 peak(count + 1, -std::numeric_limits<double>::infinity());
  for (ImageRegionConstIteratorWithIndex<ComponentImageType> it(cc, region); !it.IsAtEnd(); ++it)
  {
    const std::uint32_t c = it.Get();
    if (c == 0)
    {
      continue;
    }
    const auto index = it.GetIndex();
    if (size[c]++ == 0)
    {
      lower[c] = upper[c] = index;
    }
    for (unsigned int a = 0; a < Dimension; ++a)
    {
      lower[c][a] = std::min(lower[c][a], index[a]);
      upper[c][a] = std::max(upper[c][a], index[a]);
    }
    touches[c] = touches[c] || labels->GetPixel(index) == organ;
    peak[c] = std::max(peak[c], static_cast<double>(ct->GetPixel(index)));
  }
  double voxelVolume = 1.0;
  for (unsigned int a = 0; a < Dimension; ++a)
  {
    voxelVolume *= ct->GetSpacing()[a];
  }

  std::vector<bmr::Landmark> seeds;
  for (std::size_t c = 1; c <= count; ++c)
  {
    const double volume = double(size[c]) * voxelVolume;
    if (!touches[c] || peak[c] <= parameters.thresholdHU || volume < parameters.minimumVolume ||
        volume > parameters.maximumVolume)
    {
      continue;
    }
    // The component grown by one voxel, clipped to the image.
    typename ComponentImageType::RegionType box;
    for (unsigned int a = 0; a < Dimension; ++a)
    {
      const auto first = std::max<IndexValueType>(lower[c][a] - 1, region.GetIndex(a));
      const auto last =
        std::min<IndexValueType>(upper[c][a] + 1, region.GetIndex(a) + IndexValueType(region.GetSize(a)) - 1);
      box.SetIndex(a, first);
      box.SetSize(a, SizeValueType(last - first + 1));
    }
    double                sum = 0.0;
    std::array<double, 3> moment{ { 0, 0, 0 } };
    for (ImageRegionConstIteratorWithIndex<ComponentImageType> it(cc, box); !it.IsAtEnd(); ++it)
    {
      const auto index = it.GetIndex();
      bool       include = it.Get() == c;
      if (!include && it.Get() == 0)
      {
        // A ring voxel: a 26-neighbor of the component.
        typename ComponentImageType::RegionType neighbors;
        for (unsigned int a = 0; a < Dimension; ++a)
        {
          neighbors.SetIndex(a, index[a] - 1);
          neighbors.SetSize(a, 3);
        }
        neighbors.Crop(region);
        for (ImageRegionConstIterator<ComponentImageType> n(cc, neighbors); !include && !n.IsAtEnd(); ++n)
        {
          include = n.Get() == c;
        }
      }
      if (!include)
      {
        continue;
      }
      const double               w = std::max(0.0, static_cast<double>(ct->GetPixel(index)) - background);
      typename TImage::PointType x;
      ct->TransformIndexToPhysicalPoint(index, x);
      sum += w;
      for (unsigned int a = 0; a < Dimension && a < 3; ++a)
      {
        moment[a] += w * x[a];
      }
    }
    bmr::Landmark seed;
    seed.id = "seed" + std::to_string(seeds.size());
    for (unsigned int a = 0; a < 3; ++a)
    {
      seed.point[a] = moment[a] / sum;
    }
    seeds.push_back(seed);
  }
  return seeds;
}

} // namespace itk

#endif
