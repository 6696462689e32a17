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
// DemonsBaselineRegistrationFilter on the classic disk pair of ITK's Demons tests: a disk of radius 30
// (moving) and one of radius 32 two pixels away (fixed), 128 x 128 pixels. After registration the
// warped moving disk differs from the fixed one in at most 10 pixels (of the ~3,200 of the disk; the
// unregistered pair differs in ~500), for both Demons variants. Also: flattening makes an organ's
// interior invisible, and bad parameters are refused.
#include "itkDemonsBaselineRegistrationFilter.h"
#include "bmrTestUtilities.h"
#include "itkImageRegionIteratorWithIndex.h"
#include "itkImageWarper.h"
#include "itkTestingMacros.h"

namespace {
using ImageType = itk::Image<float, 2>;
using FieldType = itk::Image<itk::Vector<double, 2>, 2>;
using LabelImageType = itk::Image<std::int32_t, 2>;
using FilterType = itk::DemonsBaselineRegistrationFilter<ImageType, FieldType, LabelImageType>;

ImageType::Pointer
Disk(double cx, double cy, double radius)
{
  auto image = ImageType::New();
  image->SetRegions(itk::ImageRegion<2>(itk::Size<2>{ { 128, 128 } }));
  image->Allocate();
  for (itk::ImageRegionIteratorWithIndex<ImageType> it(image, image->GetLargestPossibleRegion()); !it.IsAtEnd(); ++it)
  {
    const double dx = it.GetIndex()[0] - cx;
    const double dy = it.GetIndex()[1] - cy;
    it.Set(dx * dx + dy * dy <= radius * radius ? 255.0f : 0.0f);
  }
  return image;
}

std::size_t
DifferingPixels(const ImageType * a, const ImageType * b)
{
  std::size_t n = 0;
  for (itk::ImageRegionConstIterator<ImageType> ia(a, a->GetLargestPossibleRegion()),
       ib(b, b->GetLargestPossibleRegion());
       !ia.IsAtEnd();
       ++ia, ++ib)
  {
    // Thresholded at half the disk intensity, as the binary disks are compared.
    n += (ia.Get() > 127.5f) != (ib.Get() > 127.5f);
  }
  return n;
}
} // namespace

int
itkDemonsBaselineRegistrationFilterTest(int, char *[])
{
  bool              ok = true;
  const auto        fixed = Disk(64, 64, 32);
  const auto        moving = Disk(62, 64, 30);
  const std::size_t before = DifferingPixels(fixed, moving);
  std::cout << "differing pixels before registration: " << before << std::endl;

  for (auto variant : { FilterType::VariantEnum::Diffeomorphic, FilterType::VariantEnum::FastSymmetricForces })
  {
    auto demons = FilterType::New();
    ITK_EXERCISE_BASIC_OBJECT_METHODS(demons, DemonsBaselineRegistrationFilter, ImageToImageFilter);
    demons->SetFixedImage(fixed);
    demons->SetMovingImage(moving);
    demons->SetVariant(variant);
    demons->SetNumberOfLevels(2);
    demons->SetNumberOfIterations({ 50, 100 });
    demons->SetStandardDeviation(1.0);
    demons->HistogramMatchingOff(); // binary images: nothing to match
    ITK_TRY_EXPECT_NO_EXCEPTION(demons->Update());

    auto warper = itk::ImageWarper<ImageType, FieldType>::New();
    warper->SetInput(moving);
    warper->SetDisplacementField(demons->GetOutput());
    warper->Update();
    const std::size_t after = DifferingPixels(fixed, warper->GetOutput());
    std::cout << (variant == FilterType::VariantEnum::Diffeomorphic ? "diffeomorphic" : "fast symmetric forces")
              << ": differing pixels after registration " << after << " (limit 10), final metric "
              << demons->GetFinalMetric() << std::endl;
    if (after > 10)
    {
      std::cerr << "too many differing pixels after Demons: " << after << std::endl;
      ok = false;
    }
  }

  // Flattening: a bright spot inside the "organ" of both images vanishes, so two images that differ only
  // there register to (almost) zero displacement, while without flattening the spot pulls the field.
  {
    auto labels = LabelImageType::New();
    labels->CopyInformation(fixed);
    labels->SetRegions(fixed->GetLargestPossibleRegion());
    labels->Allocate();
    auto withSpot = Disk(64, 64, 32);
    auto shiftedSpot = Disk(64, 64, 32);
    for (itk::ImageRegionIteratorWithIndex<LabelImageType> it(labels, labels->GetLargestPossibleRegion());
         !it.IsAtEnd();
         ++it)
    {
      const auto i = it.GetIndex();
      it.Set(fixed->GetPixel(i) > 0 ? 2 : 0);
      const double d1 = std::hypot(i[0] - 60.0, i[1] - 64.0), d2 = std::hypot(i[0] - 66.0, i[1] - 64.0);
      withSpot->SetPixel(i, withSpot->GetPixel(i) + (d1 <= 3.0 ? 500.0f : 0.0f));
      shiftedSpot->SetPixel(i, shiftedSpot->GetPixel(i) + (d2 <= 3.0 ? 500.0f : 0.0f));
    }
    double maximum[2] = { 0.0, 0.0 };
    for (int flatten = 0; flatten < 2; ++flatten)
    {
      auto demons = FilterType::New();
      demons->SetFixedImage(withSpot);
      demons->SetMovingImage(shiftedSpot);
      demons->HistogramMatchingOff();
      if (flatten)
      {
        demons->SetFixedLabelImage(labels);
        demons->SetMovingLabelImage(labels);
        demons->SetFlattenLabels({ 2 });
      }
      demons->Update();
      for (itk::ImageRegionConstIterator<FieldType> it(demons->GetOutput(), labels->GetLargestPossibleRegion());
           !it.IsAtEnd();
           ++it)
      {
        maximum[flatten] = std::max(maximum[flatten], it.Get().GetNorm());
      }
    }
    std::cout << "largest displacement with the spot visible " << maximum[0] << " px, flattened " << maximum[1] << " px"
              << std::endl;
    // Flattened, the images are identical: the field must stay at (numerically) zero.
    ok &= bmr::test::Expect(maximum[0] > 1.0,
                            "without flattening the spot moves the field by more than 1 px (got " +
                              bmr::test::ToString(maximum[0]) + " px)");
    ok &= bmr::test::Expect(maximum[1] < 1e-6,
                            "flattening hides the spot: field below 1e-6 px (got " + bmr::test::ToString(maximum[1]) +
                              " px)");
  }

  // Bad parameters and missing inputs are refused with an exception.
  {
    auto demons = FilterType::New();
    demons->SetFixedImage(fixed);
    ITK_TRY_EXPECT_EXCEPTION(demons->Update()); // no moving image
    demons->SetMovingImage(moving);
    demons->SetNumberOfIterations({ 10 }); // 3 levels, 1 count
    ITK_TRY_EXPECT_EXCEPTION(demons->Update());
    demons->SetNumberOfLevels(1);
    demons->SetNumberOfIterations({ 10 });
    demons->SetFlattenLabels({ 2 }); // no label images
    ITK_TRY_EXPECT_EXCEPTION(demons->Update());
    demons->SetFlattenLabels({});
    auto nan = Disk(62, 64, 30);
    nan->SetPixel({ { 3, 4 } }, std::numeric_limits<float>::quiet_NaN());
    demons->SetMovingImage(nan);
    ITK_TRY_EXPECT_EXCEPTION(demons->Update());
  }
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}
