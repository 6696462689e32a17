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
#ifndef itkGridGeometryConversion_h
#define itkGridGeometryConversion_h

#include "bmrGridGeometry.h"
#include "itkImage.h"

#include <algorithm>
#include <vector>

namespace itk {
/** Geometry of the largest possible region of an ITK image, 0-based: the origin
 * is the physical point of the region's start index. */
inline bmr::GridGeometry
GridGeometryOf(const ImageBase<3> * image)
{
  bmr::GridGeometry                g;
  const auto                       region = image->GetLargestPossibleRegion();
  typename ImageBase<3>::PointType origin;
  image->TransformIndexToPhysicalPoint(region.GetIndex(), origin);
  for (unsigned int i = 0; i < 3; ++i)
  {
    g.size[i] = region.GetSize(i);
    g.origin[i] = origin[i];
    g.spacing[i] = image->GetSpacing()[i];
    for (unsigned int j = 0; j < 3; ++j)
    {
      g.direction[3 * i + j] = image->GetDirection()(i, j);
    }
  }
  return g;
}
/** Sets \a image's spacing, origin and direction to \a grid's (its regions are left as they are). */
inline void
ApplyGridGeometry(ImageBase<3> * image, const bmr::GridGeometry & grid)
{
  ImageBase<3>::SpacingType   spacing;
  ImageBase<3>::PointType     origin;
  ImageBase<3>::DirectionType direction;
  for (unsigned int i = 0; i < 3; ++i)
  {
    spacing[i] = grid.spacing[i];
    origin[i] = grid.origin[i];
    for (unsigned int j = 0; j < 3; ++j)
    {
      direction(i, j) = grid.direction[3 * i + j];
    }
  }
  image->SetSpacing(spacing);
  image->SetOrigin(origin);
  image->SetDirection(direction);
}

/** A new image on \a grid (size, spacing, origin, direction) holding \a values, index 0 fastest
 * (the buffer layout of the bmr core). */
template<typename TImage>
typename TImage::Pointer
MakeImageOnGrid(const bmr::GridGeometry & grid, const std::vector<typename TImage::PixelType> & values)
{
  auto                        image = TImage::New();
  typename TImage::RegionType region;
  for (unsigned int i = 0; i < 3; ++i)
  {
    region.SetSize(i, grid.size[i]);
  }
  image->SetRegions(region);
  ApplyGridGeometry(image.GetPointer(), grid);
  image->Allocate();
  std::copy(values.begin(), values.end(), image->GetBufferPointer());
  return image;
}
} // namespace itk

#endif
