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
#ifndef itkIntervalTestSupport_h
#define itkIntervalTestSupport_h

#include "itkModulusInterval.h"
#include "itkNearestNeighborInterpolateImageFunction.h"
#include "itkResampleImageFilter.h"

#include <cstdlib>
#include <iostream>
#include <string>

// What the tests of the stated modulus interval share (itkModulusBootstrapTest, itkModulusRescanTest).
namespace itk {
namespace test {

/** The fixed labels on a grid of 2 mm voxels over the same extent (nearest neighbor). */
inline BiomechanicalLabelImageType::Pointer
Coarsened(const BiomechanicalLabelImageType * labels)
{
  using ResampleType = ResampleImageFilter<BiomechanicalLabelImageType, BiomechanicalLabelImageType>;
  auto resample = ResampleType::New();
  resample->SetInput(labels);
  resample->SetInterpolator(NearestNeighborInterpolateImageFunction<BiomechanicalLabelImageType>::New());
  auto size = labels->GetLargestPossibleRegion().GetSize();
  auto spacing = labels->GetSpacing();
  auto origin = labels->GetOrigin();
  for (unsigned int a = 0; a < 3; ++a)
  {
    size[a] /= 2;
    origin[a] += 0.5 * spacing[a]; // the 2 mm voxels cover the same extent
    spacing[a] *= 2.0;
  }
  resample->SetSize(size);
  resample->SetOutputSpacing(spacing);
  resample->SetOutputOrigin(origin);
  resample->SetOutputDirection(labels->GetDirection());
  resample->Update();
  return resample->GetOutput();
}

} // namespace test
} // namespace itk

#endif
