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
// The extension module _biomechreg: the pipelines of itkBiomechanicalPipelines.h on numpy arrays, the GIL released
// while they run. The package biomechreg (biomechreg/__init__.py) is its documented front; this is its engine.
#include "bmrNumerics.h"
#include "bmrPyImages.h"
#include "bmrPyModule.h"
#include "bmrPyObserver.h"
#include "itkBiomechanicalImageIO.h"
#include "itkImageWarper.h"
#include "itkMultiThreaderBase.h"

#include <pybind11/stl.h>

namespace bmrpy {

namespace {
using LabelImage = itk::BiomechanicalLabelImageType;
using CTImage = itk::BiomechanicalCTImageType;
using FieldImage = itk::BiomechanicalFieldType;

/** An unallocated image with \a image's grid: a reference geometry. */
itk::ImageBase<3>::Pointer
GridOnly(const py::tuple & image, const std::string & what)
{
  const bmr::GridGeometry grid = GeometryOf(image, what);
  auto                    reference = itk::Image<unsigned char, 3>::New();
  itk::ImageRegion<3>     region;
  for (unsigned int i = 0; i < 3; ++i)
  {
    region.SetSize(i, grid.size[i]);
  }
  reference->SetRegions(region);
  itk::ApplyGridGeometry(reference.GetPointer(), grid);
  return reference.GetPointer();
}

/** Fails (ValueError) unless \a a and \a b lie on one grid: the same size, and spacing, origin and direction equal
 * to 1e-6 (mm, or relative for the direction). */
void
CheckSameGrid(const py::tuple & a, const std::string & aName, const py::tuple & b, const std::string & bName)
{
  const auto ga = GeometryOf(a, aName);
  const auto gb = GeometryOf(b, bName);
  bool       same = ga.size == gb.size;
  for (unsigned int i = 0; i < 9; ++i)
  {
    same = same && std::abs(ga.direction[i] - gb.direction[i]) <= 1e-6;
    same = same && (i >= 3 ||
                    (std::abs(ga.spacing[i] - gb.spacing[i]) <= 1e-6 && std::abs(ga.origin[i] - gb.origin[i]) <= 1e-6));
  }
  if (!same)
  {
    throw py::value_error(aName + " and " + bName + " must lie on one grid (size, spacing, origin and direction)");
  }
}

std::shared_ptr<Registration>
Register(const py::tuple &                 movingLabels,
         const py::tuple &                 fixedLabels,
         const py::object &                movingCT,
         const py::dict &                  fixedProbabilities,
         const bmr::Scene &                scene,
         const itk::RegistrationSettings & settings,
         const py::object &                callback)
{
  const auto            moving = ImportImage<LabelImage>(movingLabels, "moving_labels");
  const auto            fixed = ImportImage<LabelImage>(fixedLabels, "fixed_labels");
  CTImage::ConstPointer ct;
  if (!movingCT.is_none())
  {
    CheckSameGrid(movingCT.cast<py::tuple>(), "moving_ct", movingLabels, "moving_labels");
    ct = ImportImage<CTImage>(movingCT.cast<py::tuple>(), "moving_ct");
  }
  itk::OrganProbabilityImages probabilities;
  for (const auto & [organ, image] : fixedProbabilities)
  {
    const auto name = organ.cast<std::string>();
    probabilities[name] =
      ImportImage<itk::BiomechanicalProbabilityImageType>(image.cast<py::tuple>(), "fixed_probabilities[" + name + "]");
  }
  PythonObserver observer(callback);
  auto           run = std::make_shared<Registration>();
  run->settings = settings;
  run->result = observer.Run(
    [&] { return itk::RegisterSegmentedPair(moving, fixed, probabilities, ct, scene, settings, &observer); });
  run->stages = run->result.state.stages;
  return run;
}

std::shared_ptr<Simulation>
Simulate(const py::tuple &  movingLabels,
         const bmr::Scene & scene,
         const py::object & reference,
         bool               pushField,
         const py::object & callback)
{
  const auto moving = ImportImage<LabelImage>(movingLabels, "moving_labels");
  const auto grid =
    reference.is_none() ? GridOnly(movingLabels, "moving_labels") : GridOnly(reference.cast<py::tuple>(), "reference");
  PythonObserver observer(callback);
  auto           run = std::make_shared<Simulation>();
  run->result = observer.Run([&] { return itk::SimulateLabelImage(moving, scene, grid, &observer, pushField); });
  return run;
}

std::shared_ptr<Phantom>
MakePhantom(const itk::PhantomSettings & settings, const py::object & callback)
{
  PythonObserver observer(callback);
  auto           run = std::make_shared<Phantom>();
  run->settings = settings;
  run->pair = observer.Run([&] { return itk::MakePhantomPair(settings, &observer); });
  return run;
}

template<typename TImage>
py::tuple
WarpAs(const py::tuple & image, const py::tuple & field, bool labels, double outside)
{
  const auto               input = ImportImage<TImage>(image, "image");
  const auto               displacement = ImportImage<FieldImage>(field, "field");
  typename TImage::Pointer warped;
  {
    py::gil_scoped_release released;
    warped = itk::WarpImage(
      input.GetPointer(), displacement.GetPointer(), labels, static_cast<typename TImage::PixelType>(outside));
  }
  return ExportImage(warped.GetPointer());
}

py::tuple
Warp(const py::tuple & image, const py::tuple & field, bool labels, double outside)
{
  return labels ? WarpAs<LabelImage>(image, field, true, outside) : WarpAs<CTImage>(image, field, false, outside);
}

template<typename TImage>
py::tuple
ReadAs(const std::string & path)
{
  typename TImage::Pointer image;
  {
    py::gil_scoped_release released;
    image = itk::ReadBiomechanicalImage<TImage>(path, "image");
  }
  return ExportImage(image.GetPointer());
}

py::tuple
ReadImage(const std::string & path, const std::string & kind)
{
  if (kind == "labels")
  {
    return ReadAs<LabelImage>(path);
  }
  if (kind == "field")
  {
    return ReadAs<FieldImage>(path);
  }
  if (kind == "ct" || kind == "probability")
  {
    return ReadAs<CTImage>(path);
  }
  throw py::value_error("kind must be \"ct\", \"labels\", \"probability\" or \"field\", got \"" + kind + "\"");
}

template<typename TImage>
void
WriteAs(const py::tuple & image, const std::string & path)
{
  const auto             input = ImportImage<TImage>(image, "image");
  py::gil_scoped_release released;
  itk::WriteImageAtomically(input.GetPointer(), path);
}

void
WriteImage(const py::tuple & image, const std::string & path)
{
  const auto array = image[0].cast<py::array>();
  if (py::isinstance<py::array_t<std::int32_t>>(array))
  {
    WriteAs<LabelImage>(image, path);
  }
  else if (array.ndim() == 4)
  {
    WriteAs<FieldImage>(image, path);
  }
  else
  {
    WriteAs<CTImage>(image, path);
  }
}

void
TranslateExceptions()
{
  py::register_exception_translator([](std::exception_ptr thrown) {
    try
    {
      std::rethrow_exception(thrown);
    }
    catch (const itk::InvalidArgumentError & e)
    {
      PyErr_SetString(PyExc_ValueError, (std::string(e.GetLocation()) + ": " + e.GetDescription()).c_str());
    }
    catch (const itk::ExceptionObject & e)
    {
      PyErr_SetString(PyExc_RuntimeError, (std::string(e.GetLocation()) + ": " + e.GetDescription()).c_str());
    }
  });
}

void
BindFunctions(py::module_ & m)
{
  m.def("register_pair", &Register);
  m.def("simulate", &Simulate);
  m.def("make_phantom", &MakePhantom);
  m.def("warp", &Warp);
  m.def("read_image", &ReadImage);
  m.def("write_image", &WriteImage);
  m.def("read_scene", [](const std::string & path) { return bmr::ReadScene(path); });
  m.def("parse_scene",
        [](const std::string & json, const std::string & source) { return bmr::ParseScene(json, source); });
  m.def("configure_numerics", [](int blasThreads) {
    const auto state = bmr::ConfigureNumerics({ blasThreads });
    return py::make_tuple(state.openBlas, state.blasThreads);
  });
  m.def("centered_grid", [](const std::array<std::size_t, 3> & size, const std::array<double, 3> & spacing, double z) {
    const auto grid = bmr::CenteredGrid(size, spacing, z);
    return py::make_tuple(grid.origin, grid.direction);
  });
  m.def("set_number_of_threads", [](unsigned int n) { itk::MultiThreaderBase::SetGlobalDefaultNumberOfThreads(n); });
  m.def("get_number_of_threads", []() { return itk::MultiThreaderBase::GetGlobalDefaultNumberOfThreads(); });
}
} // namespace

} // namespace bmrpy

PYBIND11_MODULE(_biomechreg, m)
{
  m.doc() = "The C++ engine of the package biomechreg (ITKBiomechanicalRegistration); use biomechreg itself.";
  bmrpy::TranslateExceptions();
  bmrpy::BindSettings(m);
  bmrpy::BindResults(m);
  bmrpy::BindClinical(m);
  bmrpy::BindFunctions(m);
}
