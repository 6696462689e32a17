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
#include "bmrPyImages.h"

#include <pybind11/stl.h>

#include <cmath>

namespace bmrpy {

namespace {
template<std::size_t N>
std::array<double, N>
FiniteNumbers(const py::handle & values, const std::string & what)
{
  const auto            list = py::cast<std::vector<double>>(values);
  std::array<double, N> result{};
  if (list.size() != N)
  {
    throw py::value_error(what + ": expected " + std::to_string(N) + " numbers, got " + std::to_string(list.size()));
  }
  for (std::size_t i = 0; i < N; ++i)
  {
    if (!std::isfinite(list[i]))
    {
      throw py::value_error(what + ": not a finite number");
    }
    result[i] = list[i];
  }
  return result;
}
} // namespace

bmr::GridGeometry
GeometryOf(const py::tuple & image, const std::string & what)
{
  if (image.size() != 4)
  {
    throw py::value_error(what + ": expected (array, spacing, origin, direction)");
  }
  bmr::GridGeometry grid;
  const auto        array = image[0].cast<py::array>();
  for (unsigned int i = 0; i < 3 && i < static_cast<unsigned int>(array.ndim()); ++i)
  {
    grid.size[i] = static_cast<std::size_t>(array.shape(2 - i));
  }
  grid.spacing = FiniteNumbers<3>(image[1], what + " spacing");
  grid.origin = FiniteNumbers<3>(image[2], what + " origin");
  grid.direction = FiniteNumbers<9>(image[3], what + " direction");
  try
  {
    grid.Validate(what.c_str());
  }
  catch (const itk::ExceptionObject & e)
  {
    throw py::value_error(e.GetDescription());
  }
  return grid;
}

py::tuple
ImageTuple(py::array array, const bmr::GridGeometry & grid)
{
  return py::make_tuple(array,
                        py::make_tuple(grid.spacing[0], grid.spacing[1], grid.spacing[2]),
                        py::make_tuple(grid.origin[0], grid.origin[1], grid.origin[2]),
                        py::cast(std::vector<double>(grid.direction.begin(), grid.direction.end())));
}

py::object
ToImage(const py::tuple & parts)
{
  if (parts.empty())
  {
    return py::none();
  }
  return py::module_::import("biomechreg._images").attr("Image")(parts[0], parts[1], parts[2], parts[3]);
}

} // namespace bmrpy
