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
// ImageWarper: a known translation field on a linear ramp is exact; labels stay labels and land where the field
// says (a warp in the opposite direction would move them by twice the translation).
#include "itkImageWarper.h"
#include "bmrTestUtilities.h"
#include "itkImageRegionIteratorWithIndex.h"
#include "itkTestingMacros.h"

#include <cmath>
#include <set>

int
itkImageWarperTest(int, char *[])
{
  using ImageType = itk::Image<float, 3>;
  using LabelType = itk::Image<unsigned char, 3>;
  using FieldType = itk::Image<itk::Vector<double, 3>, 3>;
  using bmr::test::Expect;
  using bmr::test::ToString;
  bool ok = true;

  auto         image = ImageType::New();
  auto         labels = LabelType::New();
  itk::Size<3> size = { { 24, 20, 10 } };
  const double spacing[3] = { 1.0, 1.5, 2.0 };
  for (itk::ImageBase<3> * im : { static_cast<itk::ImageBase<3> *>(image), static_cast<itk::ImageBase<3> *>(labels) })
  {
    im->SetRegions(itk::ImageRegion<3>(size));
    im->SetSpacing(spacing);
  }
  image->Allocate();
  labels->Allocate();
  for (itk::ImageRegionIteratorWithIndex<ImageType> it(image, image->GetLargestPossibleRegion()); !it.IsAtEnd(); ++it)
  {
    ImageType::PointType p;
    image->TransformIndexToPhysicalPoint(it.GetIndex(), p);
    it.Set(static_cast<float>(3.0 * p[0] - 2.0 * p[1] + p[2]));
    labels->SetPixel(it.GetIndex(), static_cast<unsigned char>(p[0] < 8 ? 1 : (p[1] < 12 ? 2 : 7)));
  }
  // Field: translation by (2.3, -1.2, 0.7) mm, fixed -> moving; no component is a half voxel, so that nearest
  // neighbour has no ties.
  auto field = FieldType::New();
  field->CopyInformation(image);
  field->SetRegions(image->GetLargestPossibleRegion());
  field->Allocate();
  FieldType::PixelType t;
  t[0] = 2.3;
  t[1] = -1.2;
  t[2] = 0.7;
  field->FillBuffer(t);

  using WarperType = itk::ImageWarper<ImageType, FieldType>;
  auto warper = WarperType::New();
  ITK_EXERCISE_BASIC_OBJECT_METHODS(warper, ImageWarper, ImageToImageFilter);
  warper->SetInput(image);
  warper->SetDisplacementField(field);
  warper->SetDefaultPixelValue(-1000.0f);
  // Float images default to linear interpolation, integer (label) images to nearest neighbor.
  ok &= Expect(warper->GetInterpolation() == WarperType::InterpolationEnum::Linear,
               "a float image defaults to linear interpolation (got mode " +
                 ToString(static_cast<int>(warper->GetInterpolation())) + ")");
  warper->Update();
  double      worst = 0.0;
  std::size_t inside = 0;
  for (itk::ImageRegionIteratorWithIndex<ImageType> it(warper->GetOutput(), image->GetLargestPossibleRegion());
       !it.IsAtEnd();
       ++it)
  {
    ImageType::PointType p;
    image->TransformIndexToPhysicalPoint(it.GetIndex(), p);
    const double q[3] = { p[0] + t[0], p[1] + t[1], p[2] + t[2] };
    if (q[0] >= 0 && q[0] <= 23 && q[1] >= 0 && q[1] <= 28.5 && q[2] >= 0 && q[2] <= 18)
    {
      ++inside;
      worst = std::max(worst, std::abs(it.Get() - (3.0 * q[0] - 2.0 * q[1] + q[2])));
    }
  }
  std::cout << "linear ramp through a translation: max error " << worst << " over " << inside << " voxels" << std::endl;
  // 1e-3: linear interpolation of a linear function is exact; float pixels round at ~1e-5 relative.
  ok &= Expect(inside > 1000, "more than 1000 voxels map inside the image (got " + ToString(inside) + ")");
  ok &= Expect(worst < 1e-3, "linear ramp through a translation exact to 1e-3 (got max error " + ToString(worst) + ")");

  // Labels: nearest neighbour and label-Gaussian return only input labels, each voxel the label found at p + t.
  // Nearest neighbour is exact wherever p + t lies inside the image; label-Gaussian (sigma one voxel) wherever
  // p + t is at least 3 mm from a boundary between labels (the planes x = 8 and, for x >= 8, y = 12).
  const auto labelAt = [&](const double q[3]) {
    LabelType::IndexType index;
    for (unsigned int a = 0; a < 3; ++a)
    {
      index[a] = static_cast<itk::IndexValueType>(std::lround(q[a] / spacing[a]));
    }
    return static_cast<int>(labels->GetPixel(index));
  };
  for (auto mode : { itk::ImageWarper<LabelType, FieldType>::InterpolationEnum::NearestNeighbor,
                     itk::ImageWarper<LabelType, FieldType>::InterpolationEnum::LabelGaussian })
  {
    const bool nearest = mode == itk::ImageWarper<LabelType, FieldType>::InterpolationEnum::NearestNeighbor;
    auto       lw = itk::ImageWarper<LabelType, FieldType>::New();
    lw->SetInput(labels);
    lw->SetDisplacementField(field);
    lw->SetInterpolation(mode);
    lw->Update();
    std::set<int> seen;
    std::size_t   checked = 0, misplaced = 0;
    for (itk::ImageRegionIteratorWithIndex<LabelType> it(lw->GetOutput(), labels->GetLargestPossibleRegion());
         !it.IsAtEnd();
         ++it)
    {
      seen.insert(it.Get());
      LabelType::PointType p;
      labels->TransformIndexToPhysicalPoint(it.GetIndex(), p);
      const double q[3] = { p[0] + t[0], p[1] + t[1], p[2] + t[2] };
      const bool   inside = q[0] >= 0 && q[0] <= 23 && q[1] >= 0 && q[1] <= 28.5 && q[2] >= 0 && q[2] <= 18;
      const bool   nearBoundary = std::abs(q[0] - 8.0) < 3.0 || (q[0] >= 5.0 && std::abs(q[1] - 12.0) < 3.0);
      if (inside && (nearest || !nearBoundary))
      {
        ++checked;
        misplaced += static_cast<int>(it.Get()) != labelAt(q) ? 1 : 0;
      }
    }
    const bool preserved = seen == std::set<int>({ 0, 1, 2, 7 });
    std::cout << "label interpolation " << static_cast<int>(mode) << ": labels preserved " << preserved << ", "
              << misplaced << " of " << checked << " voxels with another label than at p + t" << std::endl;
    ok &= Expect(preserved,
                 "label interpolation " + ToString(static_cast<int>(mode)) +
                   " returns exactly the labels {0, 1, 2, 7} (got " + ToString(seen.size()) + " distinct values)");
    ok &=
      Expect(checked > 500 && misplaced == 0,
             "label interpolation " + ToString(static_cast<int>(mode)) + " puts every checked voxel's label where " +
               "the field says (" + ToString(misplaced) + " of " + ToString(checked) + " misplaced)");
  }
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}
