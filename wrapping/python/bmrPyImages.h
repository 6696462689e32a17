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
#ifndef bmrPyImages_h
#define bmrPyImages_h

// numpy arrays <-> ITK images for the Python package, without copying the voxels.
#include "bmrGridGeometry.h"
#include "itkGridGeometryConversion.h"
#include "itkImage.h"
#include "itkImportImageContainer.h"
#include "itkNumericTraits.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <string>

namespace bmrpy {
namespace py = pybind11;

/** An image as the Python layer hands it over: (array [z, y, x] or [z, y, x, 3], spacing, origin, direction with
 * nine row-major entries), the geometry in x, y, z order, LPS mm. */
bmr::GridGeometry
GeometryOf(const py::tuple & image, const std::string & what);

/** The tuple the Python layer makes a biomechreg.Image of: (array, spacing, origin, direction). */
py::tuple
ImageTuple(py::array array, const bmr::GridGeometry & grid);

/** A biomechreg.Image of the engine's (array, spacing, origin, direction); None for an empty tuple (a null
 * image). */
py::object
ToImage(const py::tuple & parts);

/** The number of scalars per pixel (3 for a displacement vector) and their type. */
template<typename TPixel>
struct PixelLayout
{
  using Scalar = typename itk::NumericTraits<TPixel>::ValueType;
  static constexpr unsigned int Components = sizeof(TPixel) / sizeof(Scalar);
};

/** An ITK image that reads the voxels of \a image's array in place (the array must outlive it): the array must be
 * C-contiguous, of TPixel's scalar type, 3-D (4-D with a last axis of 3 for vectors), as the Python layer makes it;
 * anything else is a ValueError naming \a what. */
template<typename TImage>
typename TImage::Pointer
ImportImage(const py::tuple & image, const std::string & what)
{
  using Layout = PixelLayout<typename TImage::PixelType>;
  const bmr::GridGeometry grid = GeometryOf(image, what);
  const auto              array = image[0].cast<py::array>();
  const bool              vector = Layout::Components > 1;
  const py::ssize_t       dims = vector ? 4 : 3;
  if (array.ndim() != dims || (vector && array.shape(3) != Layout::Components) ||
      !py::isinstance<py::array_t<typename Layout::Scalar>>(array) || !(array.flags() & py::array::c_style))
  {
    throw py::value_error(what + ": expected a C-contiguous " + std::to_string(dims) + "-D array of " +
                          py::str(py::dtype::of<typename Layout::Scalar>()).cast<std::string>());
  }
  auto                        result = TImage::New();
  typename TImage::RegionType region;
  for (unsigned int i = 0; i < 3; ++i)
  {
    region.SetSize(i, static_cast<itk::SizeValueType>(array.shape(2 - i)));
  }
  auto container = TImage::PixelContainer::New();
  auto pixels = reinterpret_cast<typename TImage::PixelType *>(const_cast<void *>(array.data()));
  container->SetImportPointer(pixels, region.GetNumberOfPixels(), false);
  result->SetRegions(region);
  result->SetPixelContainer(container);
  itk::ApplyGridGeometry(result.GetPointer(), grid);
  return result;
}

/** \a image as (array, spacing, origin, direction); the array views the image's buffer and keeps the image alive. */
template<typename TImage>
py::tuple
ExportImage(const TImage * image)
{
  using Layout = PixelLayout<typename TImage::PixelType>;
  if (image == nullptr)
  {
    return py::tuple();
  }
  const auto               size = image->GetBufferedRegion().GetSize();
  std::vector<py::ssize_t> shape{ py::ssize_t(size[2]), py::ssize_t(size[1]), py::ssize_t(size[0]) };
  if (Layout::Components > 1)
  {
    shape.push_back(Layout::Components);
  }
  auto        keep = new typename TImage::ConstPointer(image);
  py::capsule owner(keep, [](void * p) { delete static_cast<typename TImage::ConstPointer *>(p); });
  const auto  scalars = reinterpret_cast<const typename Layout::Scalar *>(image->GetBufferPointer());
  py::array   array(py::dtype::of<typename Layout::Scalar>(), shape, scalars, owner);
  return ImageTuple(array, itk::GridGeometryOf(image));
}

} // namespace bmrpy

#endif
