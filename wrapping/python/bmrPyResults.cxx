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
// Results as Python classes whose properties hand out numpy views of the C++ images (biomechreg.Image) and plain
// dicts; write() writes them as the command line does.
#include "bmrLandmarks.h"
#include "bmrPyImages.h"
#include "bmrPyModule.h"
#include "itkBiomechanicalReports.h"
#include "itkBiomechanicalWriters.h"

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

namespace bmrpy {

namespace {
/** \a image as a biomechreg.Image (None for a null image), viewing its voxels. */
template<typename TImage>
py::object
PyImage(const TImage * image)
{
  if (image == nullptr)
  {
    return py::none();
  }
  const py::tuple parts = ExportImage(image);
  return py::module_::import("biomechreg._images").attr("Image")(parts[0], parts[1], parts[2], parts[3]);
}

template<typename TImage>
py::dict
PyImages(const std::map<std::string, TImage> & images)
{
  py::dict result;
  for (const auto & [name, image] : images)
  {
    result[py::str(name)] = PyImage(image.GetPointer());
  }
  return result;
}

/** The mesh as numpy arrays: points (N, 3) [mm], tetrahedra (M, 4), labels (M,), displacement (N, 3) [mm] and
 * force (N, 3) [mN] when present. */
py::dict
MeshArrays(const bmr::TetrahedralMesh & mesh)
{
  const auto nodes = static_cast<py::ssize_t>(mesh.GetNumberOfPoints());
  const auto cells = static_cast<py::ssize_t>(mesh.GetNumberOfTetrahedra());
  py::dict   arrays;
  arrays["points"] = py::array_t<double>({ nodes, py::ssize_t(3) }, mesh.points.data());
  arrays["tetrahedra"] = py::array_t<std::int32_t>({ cells, py::ssize_t(4) }, mesh.tetrahedra.data());
  arrays["labels"] = py::array_t<std::int32_t>({ cells }, mesh.labels.data());
  if (mesh.displacement.size() == mesh.points.size())
  {
    arrays["displacement"] = py::array_t<double>({ nodes, py::ssize_t(3) }, mesh.displacement.data());
  }
  if (mesh.force.size() == mesh.points.size())
  {
    arrays["force"] = py::array_t<double>({ nodes, py::ssize_t(3) }, mesh.force.data());
  }
  return arrays;
}

py::dict
IntervalDict(const std::string & name, const itk::ModulusInterval & i)
{
  py::dict d;
  d["fit"] = i.fit;
  d["estimate"] = i.estimate;
  d["interval68"] = i.interval68;
  d["interval95"] = i.interval95;
  d["lower_determined"] = i.lowerDetermined;
  d["upper_determined"] = i.upperDetermined;
  d["log_sigma"] = i.logSigma;
  d["method"] = i.method;
  d["quantiles"] = i.quantiles;
  d["resample_moduli"] = i.resampleModuli;
  d["not_determined_reason"] = i.notDeterminedReason;
  d["text"] = itk::ModulusIntervalText(name, i);
  return d;
}

/** Landmark id -> (x, y, z) [mm, LPS], in the landmarks' order. */
py::dict
LandmarkDict(const std::vector<bmr::Landmark> & landmarks)
{
  py::dict d;
  for (const auto & l : landmarks)
  {
    d[py::str(l.id)] = py::make_tuple(l.point[0], l.point[1], l.point[2]);
  }
  return d;
}

py::object
JsonToPython(const std::string & json)
{
  return py::module_::import("json").attr("loads")(json);
}

std::vector<std::pair<std::string, double>>
StageList(const std::vector<itk::PipelineStage> & stages)
{
  std::vector<std::pair<std::string, double>> list;
  for (const auto & s : stages)
  {
    list.emplace_back(s.name, s.seconds);
  }
  return list;
}

void
BindScene(py::module_ & m)
{
  py::class_<bmr::Scene>(m, "Scene", "What each label is, what carries loads, what is matched (docs/scenes.md).")
    .def_readonly("name", &bmr::Scene::name)
    .def("to_json", &bmr::SceneToJson, "The scene as JSON text, the format read_scene() reads.")
    .def_property_readonly(
      "labels",
      [](const bmr::Scene & s) {
        py::dict labels;
        for (const auto & l : s.labels)
        {
          labels[py::str(l.name)] = l.value;
        }
        return labels;
      },
      "Label name -> value in the label map.")
    .def_property_readonly(
      "unknown_labels",
      [](const bmr::Scene & s) {
        std::vector<std::string> names;
        for (const auto * l : s.UnknownLabels())
        {
          names.push_back(l->name);
        }
        return names;
      },
      "The labels whose modulus is estimated.")
    .def_property_readonly("objective_labels",
                           [](const bmr::Scene & s) {
                             std::vector<std::string> names;
                             for (const auto & t : s.objective)
                             {
                               names.push_back(t.label);
                             }
                             return names;
                           })
    .def("__repr__", [](const bmr::Scene & s) { return "<biomechreg.Scene \"" + s.name + "\">"; });
}

void
BindRegistration(py::module_ & m)
{
  py::class_<Registration, std::shared_ptr<Registration>>(m, "Registration", "What register() found.")
    .def_property_readonly(
      "youngs_modulus", [](const Registration & r) { return r.result.youngsModulus; }, "kPa by label")
    .def_property_readonly(
      "intervals",
      [](const Registration & r) {
        py::dict d;
        for (const auto & [name, interval] : r.result.modulusInterval)
        {
          d[py::str(name)] = IntervalDict(name, interval);
        }
        return d;
      },
      "The stated interval per unknown label (kPa), with the text register prints.")
    .def_property_readonly("modulus_text",
                           [](const Registration & r) {
                             py::dict d;
                             for (const auto & kv : r.result.youngsModulus)
                             {
                               d[py::str(kv.first)] = itk::RecoveredModulusText(r.result, kv.first);
                             }
                             return d;
                           })
    .def_property_readonly(
      "report",
      [](const Registration & r) { return JsonToPython(itk::RegistrationReportJson(r.result, r.settings, r.stages)); },
      "report.json's content as a dict.")
    .def_property_readonly(
      "field",
      [](const Registration & r) { return PyImage(r.result.state.pullBack.GetPointer()); },
      "fixed -> moving [mm] on the fixed grid")
    .def_property_readonly(
      "push_field",
      [](const Registration & r) { return PyImage(r.result.state.push.GetPointer()); },
      "moving -> fixed [mm], with push_field=True")
    .def_property_readonly("warped_labels",
                           [](const Registration & r) { return PyImage(r.result.warpedLabels.GetPointer()); })
    .def_property_readonly("warped_ct", [](const Registration & r) { return PyImage(r.result.warpedCT.GetPointer()); })
    .def_property_readonly("mesh", [](const Registration & r) { return MeshArrays(r.result.state.mesh); })
    .def_property_readonly("dice", [](const Registration & r) { return r.result.dice; })
    .def_property_readonly("inverted_elements", [](const Registration & r) { return r.result.state.invertedElements; })
    .def_property_readonly("jacobian_minimum", [](const Registration & r) { return r.result.jacobianMinimum; })
    .def_property_readonly("identifiable", [](const Registration & r) { return r.result.estimation.identifiable; })
    .def_property_readonly("warnings", [](const Registration & r) { return r.result.state.warnings; })
    .def_property_readonly(
      "stages", [](const Registration & r) { return StageList(r.stages); }, "(stage, seconds)")
    .def(
      "write",
      [](const Registration & r, const std::filesystem::path & directory, const std::string & outputs) {
        const auto             which = itk::RegistrationOutputs::Parse(outputs);
        py::gil_scoped_release released;
        itk::WriteRegistrationOutputs(directory.string(), r.result, r.settings, r.stages, which);
      },
      py::arg("directory"),
      py::arg("outputs") = "default",
      "Writes the files biomechreg register writes (outputs: as its --outputs).");
}

void
BindPhantom(py::module_ & m)
{
  py::class_<Phantom, std::shared_ptr<Phantom>>(m, "Phantom", "A moving/fixed pair with its ground truth.")
    .def_property_readonly("moving_ct", [](const Phantom & p) { return PyImage(p.pair.movingCT.GetPointer()); })
    .def_property_readonly("fixed_ct", [](const Phantom & p) { return PyImage(p.pair.fixedCT.GetPointer()); })
    .def_property_readonly("moving_labels", [](const Phantom & p) { return PyImage(p.pair.movingLabels.GetPointer()); })
    .def_property_readonly("fixed_labels", [](const Phantom & p) { return PyImage(p.pair.fixedLabels.GetPointer()); })
    .def_property_readonly(
      "truth_field", [](const Phantom & p) { return PyImage(p.pair.truthField.GetPointer()); }, "fixed -> moving [mm]")
    .def_property_readonly("fixed_fractions", [](const Phantom & p) { return PyImages(p.pair.fixedFractions); })
    .def_property_readonly("fixed_contour_fractions",
                           [](const Phantom & p) { return PyImages(p.pair.fixedContourFractions); })
    .def_property_readonly(
      "scene", [](const Phantom & p) { return p.pair.scene; }, "What the estimator sees.")
    .def_property_readonly("truth_scene", [](const Phantom & p) { return p.pair.truthScene; })
    .def_property_readonly(
      "truth",
      [](const Phantom & p) { return JsonToPython(itk::PhantomTruthJson(p.pair, p.settings)); },
      "truth.json's content as a dict.")
    .def_property_readonly(
      "moving_landmarks",
      [](const Phantom & p) { return LandmarkDict(p.pair.movingLandmarks); },
      "seed id -> (x, y, z) [mm, LPS]")
    .def_property_readonly("fixed_landmarks", [](const Phantom & p) { return LandmarkDict(p.pair.fixedLandmarks); })
    .def_property_readonly("tracked_landmarks", [](const Phantom & p) { return LandmarkDict(p.pair.trackedLandmarks); })
    .def(
      "write",
      [](const Phantom & p, const std::filesystem::path & directory) {
        py::gil_scoped_release released;
        itk::WritePhantomPair(directory.string(), p.pair, p.settings);
      },
      py::arg("directory"),
      "Writes the files biomechreg phantom writes.");
}

void
BindSimulation(py::module_ & m)
{
  py::class_<Simulation, std::shared_ptr<Simulation>>(m, "Simulation", "What simulate() computed.")
    .def_property_readonly(
      "field",
      [](const Simulation & s) { return PyImage(s.result.pullBack.GetPointer()); },
      "fixed -> moving [mm] on the reference grid")
    .def_property_readonly(
      "push_field",
      [](const Simulation & s) { return PyImage(s.result.push.GetPointer()); },
      "moving -> fixed [mm] on the moving grid")
    .def_property_readonly("mesh", [](const Simulation & s) { return MeshArrays(s.result.mesh); })
    .def_property_readonly("inverted_elements", [](const Simulation & s) { return s.result.invertedElements; })
    .def_property_readonly("warnings", [](const Simulation & s) { return s.result.warnings; })
    .def_property_readonly("stages", [](const Simulation & s) { return StageList(s.result.stages); });
}
} // namespace

void
BindResults(py::module_ & m)
{
  BindScene(m);
  BindRegistration(m);
  BindPhantom(m);
  BindSimulation(m);
}

} // namespace bmrpy
