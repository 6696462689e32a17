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
// The clinical pipelines for the package: markers (itk::EstimateTreatmentFromMarkers, dissertation chapter 4) and
// dose (itk::EvaluateDose, itk::MakeConformalDosePlan, itk::WarpDose).
#include "bmrLandmarks.h"
#include "bmrPyImages.h"
#include "bmrPyModule.h"
#include "bmrPyObserver.h"
#include "itkBiomechanicalImageIO.h"
#include "itkClinicalStructureSet.h"
#include "itkBiomechanicalWriters.h"
#include "itkDicomRT.h"
#include "itkDicomRTWriters.h"
#include "itkDoseEvaluation.h"
#include "itkMarkerPipeline.h"

#include <pybind11/stl.h>

namespace bmrpy {

namespace {
using LabelImage = itk::BiomechanicalLabelImageType;
using CTImage = itk::BiomechanicalCTImageType;

/** {id: (x, y, z)} [mm, LPS] as the library's landmarks, in the dict's order. */
std::vector<bmr::Landmark>
Landmarks(const py::dict & points, const std::string & what)
{
  std::vector<bmr::Landmark> landmarks;
  for (const auto & [id, point] : points)
  {
    const auto xyz = point.cast<std::vector<double>>();
    if (xyz.size() != 3 || !std::isfinite(xyz[0]) || !std::isfinite(xyz[1]) || !std::isfinite(xyz[2]))
    {
      throw py::value_error(what + "[" + py::str(id).cast<std::string>() + "]: expected three finite numbers [mm]");
    }
    landmarks.push_back({ py::str(id).cast<std::string>(), { { xyz[0], xyz[1], xyz[2] } } });
  }
  return landmarks;
}

py::dict
MethodDict(const itk::MarkerMethodResult & m)
{
  py::dict d;
  d["fit_residual_mm"] = m.fitResidual;
  d["leave_one_out_error_mm"] = m.leaveOneOutError;
  d["leave_one_out_rms_mm"] = m.leaveOneOutRms;
  d["intersection_over_union"] = m.intersectionOverUnion;
  d["mean_surface_distance_mm"] = m.meanSurfaceDistance;
  d["warped_labels"] = ToImage(ExportImage(m.warpedLabels.GetPointer()));
  d["field"] = ToImage(ExportImage(m.field.GetPointer()));
  return d;
}

std::shared_ptr<Markers>
EstimateFromMarkers(const py::tuple &           planningLabels,
                    const py::tuple &           planningCT,
                    const bmr::Scene &          scene,
                    const py::dict &            planningMarkers,
                    const py::dict &            treatmentMarkers,
                    const py::object &          treatmentLabels,
                    const itk::MarkerSettings & settings,
                    const py::object &          callback)
{
  const auto          labels = ImportImage<LabelImage>(planningLabels, "planning_labels");
  const auto          ct = ImportImage<CTImage>(planningCT, "planning_ct");
  const auto          planning = Landmarks(planningMarkers, "planning_markers");
  const auto          treatment = Landmarks(treatmentMarkers, "treatment_markers");
  LabelImage::Pointer evaluation;
  if (!treatmentLabels.is_none())
  {
    evaluation = ImportImage<LabelImage>(treatmentLabels.cast<py::tuple>(), "treatment_labels");
  }
  const bmr::SceneLabel * organ = scene.FindLabel(settings.organ);
  PythonObserver          observer(callback);
  auto                    run = std::make_shared<Markers>();
  run->settings = settings;
  run->result = observer.Run([&] {
    auto result = itk::EstimateTreatmentFromMarkers(labels, ct, scene, planning, treatment, settings, &observer);
    if (evaluation && organ != nullptr)
    {
      itk::EvaluateMarkerMethods(result, evaluation, organ->value);
    }
    return result;
  });
  return run;
}

py::dict
StructureDict(const itk::StructureDose & s)
{
  py::dict d;
  d["label"] = s.label;
  d["volume_cc"] = s.metrics.volumeCC;
  d["mean_Gy"] = s.metrics.mean;
  d["minimum_Gy"] = s.metrics.minimum;
  d["maximum_Gy"] = s.metrics.maximum;
  d["D95_Gy"] = s.metrics.D95;
  d["D98_Gy"] = s.metrics.D98;
  d["D2_Gy"] = s.metrics.D2;
  d["eud_a"] = s.metrics.eudA;
  d["gEUD_Gy"] = s.metrics.gEUD;
  py::dict volumes;
  for (const auto & v : s.metrics.volumesAtDose)
  {
    volumes[py::float_(v.doseGy)] = v.fraction;
  }
  d["volume_fraction_at_dose"] = volumes;
  d["dvh_cumulative"] = py::array_t<double>(s.dvh.cumulative.size(), s.dvh.cumulative.data());
  d["dvh_differential"] = py::array_t<double>(s.dvh.differential.size(), s.dvh.differential.data());
  d["fraction_outside_dose_grid"] = s.fractionOutsideDoseGrid;
  return d;
}

py::dict
EvaluateDose(const py::tuple &                   labels,
             const py::tuple &                   dose,
             const bmr::Scene &                  scene,
             const py::object &                  field,
             const itk::DoseEvaluationSettings & settings)
{
  const auto                           labelImage = ImportImage<LabelImage>(labels, "labels");
  auto                                 doseImage = ImportImage<itk::BiomechanicalDoseImageType>(dose, "dose");
  itk::BiomechanicalFieldType::Pointer displacement;
  if (!field.is_none())
  {
    displacement = ImportImage<itk::BiomechanicalFieldType>(field.cast<py::tuple>(), "field");
  }
  itk::DoseEvaluation evaluation;
  {
    py::gil_scoped_release released;
    if (displacement)
    {
      doseImage = itk::WarpDose(doseImage, displacement);
    }
    evaluation = itk::EvaluateDose(labelImage, doseImage, itk::DoseStructuresFromScene(scene), settings);
  }
  py::dict structures;
  for (const auto & s : evaluation.structures)
  {
    structures[py::str(s.name)] = StructureDict(s);
  }
  py::dict result;
  result["structures"] = structures;
  result["bin_width_Gy"] = evaluation.binWidthGy;
  result["dose_resampled"] = evaluation.doseResampled;
  result["dose"] = ToImage(ExportImage(doseImage.GetPointer()));
  result["metrics_csv"] = itk::DoseMetricsCsv(evaluation);
  result["dvh_csv"] = itk::DoseVolumeHistogramCsv(evaluation);
  return result;
}

py::object
ConformalPlan(const py::tuple &                  labels,
              const bmr::Scene &                 scene,
              const std::string &                prostate,
              const itk::ConformalPlanSettings & settings)
{
  const auto              labelImage = ImportImage<LabelImage>(labels, "labels");
  const bmr::SceneLabel * organ = scene.FindLabel(prostate);
  if (organ == nullptr)
  {
    throw py::value_error("prostate: the scene has no label \"" + prostate + "\"");
  }
  itk::BiomechanicalDoseImageType::Pointer plan;
  {
    py::gil_scoped_release released;
    plan = itk::MakeConformalDosePlan(labelImage, organ->value, settings);
  }
  return ToImage(ExportImage(plan.GetPointer()));
}

/** The CT of a structure set: the path of its series (read with its DICOM attributes) or an image. */
CTImage::Pointer
StructureSetCT(const py::object & ct)
{
  if (!py::isinstance<py::str>(ct))
  {
    return ImportImage<CTImage>(ct.cast<py::tuple>(), "ct");
  }
  const auto             path = ct.cast<std::string>();
  py::gil_scoped_release released;
  return itk::ReadBiomechanicalImage<CTImage>(path, "ct");
}

/** Each ROI's area fractions per voxel of the CT's grid (itk::ReadRTStructAreaFractions), by ROI name. */
py::dict
ReadOutlineFractions(const std::string & rtstruct, const py::object & ct, const std::vector<std::string> & rois)
{
  const CTImage::Pointer                                                 grid = StructureSetCT(ct);
  std::map<std::string, itk::BiomechanicalProbabilityImageType::Pointer> fractions;
  {
    py::gil_scoped_release released;
    for (auto & [name, image] : itk::ReadRTStructAreaFractions(rtstruct, grid, rois))
    {
      fractions[name] = image;
    }
  }
  py::dict result;
  for (const auto & [name, image] : fractions)
  {
    result[py::str(name)] = ToImage(ExportImage(image.GetPointer()));
  }
  return result;
}

/** Which ROI became which part, and the bone's origin, as a dict. */
py::dict
MappingDict(const itk::ClinicalAnatomy & anatomy)
{
  py::dict mapping;
  mapping["part_of_roi"] = anatomy.mapping.partOfROI;
  mapping["left_out"] = anatomy.mapping.leftOut;
  mapping["bone_from_ct"] = anatomy.boneFromCT;
  mapping["bone_voxels"] = anatomy.boneVoxels;
  mapping["bone_pieces_dropped"] = anatomy.bonePiecesDropped;
  return mapping;
}

/** The built-in pelvis scene's label map from a structure set (itk::ReadClinicalPelvisAnatomy) and its mapping; the
 * CT given as an image (no DICOM attributes) or as the path of its series (its frame of reference checked). */
py::tuple
ReadStructureSet(const std::string &                        rtstruct,
                 const py::object &                         ct,
                 const std::map<std::string, std::string> & overrides,
                 const itk::ClinicalAnatomySettings &       settings)
{
  CTImage::Pointer image;
  if (py::isinstance<py::str>(ct))
  {
    const auto             path = ct.cast<std::string>();
    py::gil_scoped_release released;
    image = itk::ReadBiomechanicalImage<CTImage>(path, "ct");
  }
  else
  {
    image = ImportImage<CTImage>(ct.cast<py::tuple>(), "ct");
  }
  itk::ClinicalAnatomy anatomy;
  {
    py::gil_scoped_release released;
    anatomy = itk::ReadClinicalPelvisAnatomy(rtstruct, image, overrides, settings);
  }
  return py::make_tuple(ToImage(ExportImage(anatomy.labels.GetPointer())), MappingDict(anatomy));
}

/** The built-in scene's label map from a named label map (itk::ClinicalPelvisAnatomyFromLabelMap) and its
 * mapping. */
py::tuple
ReadNamedLabelMap(const py::tuple &                           labels,
                  const std::map<std::int32_t, std::string> & names,
                  const py::object &                          ct,
                  const std::map<std::string, std::string> &  overrides,
                  const itk::ClinicalAnatomySettings &        settings)
{
  const auto           labelImage = ImportImage<itk::BiomechanicalLabelImageType>(labels, "labels");
  const auto           image = StructureSetCT(ct);
  itk::ClinicalAnatomy anatomy;
  {
    py::gil_scoped_release released;
    anatomy = itk::ClinicalPelvisAnatomyFromLabelMap(labelImage, names, image, overrides, settings, "labels");
  }
  return py::make_tuple(ToImage(ExportImage(anatomy.labels.GetPointer())), MappingDict(anatomy));
}

void
BindStructureSets(py::module_ & m)
{
  using C = itk::ClinicalAnatomySettings;
  py::class_<C>(m, "ClinicalAnatomySettings", "How bone is found in the CT (itk::ClinicalAnatomySettings).")
    .def(py::init<>())
    .def_readwrite("bone_threshold_HU", &C::boneThresholdHU)
    .def_readwrite("minimum_bone_volume_cc", &C::minimumBoneVolumeCC);
  m.def("read_structure_set", &ReadStructureSet);
  m.def("read_named_label_map", &ReadNamedLabelMap);
  m.def("read_label_names", &itk::ReadLabelNames);
  m.def("read_outline_fractions", &ReadOutlineFractions);
  m.def("builtin_pelvis_scene", &itk::BuiltInPelvisScene);
}

void
BindMarkers(py::module_ & m)
{
  using S = itk::MarkerSettings;
  py::class_<S>(m, "MarkerSettings", "Settings of markers() (itk::MarkerSettings).")
    .def(py::init<>())
    .def_readwrite("organ", &S::organ)
    .def_readwrite("box_margin_mm", &S::boxMargin)
    .def_readwrite("control_spacing_mm", &S::controlSpacing)
    .def_readwrite("regularization", &S::regularization)
    .def_readwrite("mesh_scale", &S::meshScale)
    .def_readwrite("moduli", &S::moduli, "kPa by scene label")
    .def_readwrite("maximum_iterations", &S::maximumIterations)
    .def_readwrite("leave_one_out", &S::leaveOneOut);
  py::class_<Markers, std::shared_ptr<Markers>>(m, "Markers", "What markers() estimated.")
    .def_property_readonly(
      "field",
      [](const Markers & r) { return ToImage(ExportImage(r.result.state.pullBack.GetPointer())); },
      "treatment -> planning [mm] on the planning grid")
    .def_property_readonly("warped_ct",
                           [](const Markers & r) { return ToImage(ExportImage(r.result.warpedCT.GetPointer())); })
    .def_property_readonly(
      "methods",
      [](const Markers & r) {
        py::dict d;
        for (const auto & method : r.result.methods)
        {
          d[py::str(method.method)] = MethodDict(method);
        }
        return d;
      },
      "fem, rigid, tps: residuals, leave-one-out errors, IoU and D, warped labels, field")
    .def_property_readonly("marker_ids", [](const Markers & r) { return r.result.markerIds; })
    .def_property_readonly("warnings", [](const Markers & r) { return r.result.warnings; })
    .def_property_readonly(
      "report",
      [](const Markers & r) {
        return py::module_::import("json").attr("loads")(itk::MarkerReportJson(r.result, r.settings));
      },
      "report.json of biomechreg markers, as a dict");
  m.def("markers", &EstimateFromMarkers);
}

void
BindDose(py::module_ & m)
{
  using D = itk::DoseEvaluationSettings;
  py::class_<D>(m, "DoseEvaluationSettings", "Settings of dose() (itk::DoseEvaluationSettings).")
    .def(py::init<>())
    .def_readwrite("bin_width_Gy", &D::binWidthGy)
    .def_readwrite("volume_doses_Gy", &D::volumeDosesGy)
    .def_readwrite("eud_parameters", &D::eudParameters)
    .def_readwrite("anterior_rectal_wall", &D::anteriorRectalWall);
  using P = itk::ConformalPlanSettings;
  py::class_<P>(m, "ConformalPlanSettings", "Settings of conformal_plan() (itk::ConformalPlanSettings).")
    .def(py::init<>())
    .def_readwrite("margin_mm", &P::marginMm)
    .def_readwrite("prescription_Gy", &P::prescriptionGy)
    .def_readwrite("penumbra_mm", &P::penumbraMm)
    .def_readwrite("bath_fraction", &P::bathFraction)
    .def_readwrite("bath_length_mm", &P::bathLengthMm);
  m.def("dose", &EvaluateDose);
  m.def("conformal_plan", &ConformalPlan);
  m.def("read_landmarks", [](const std::string & path) {
    py::dict points;
    for (const auto & l : bmr::ReadLandmarks(path))
    {
      points[py::str(l.id)] = py::make_tuple(l.point[0], l.point[1], l.point[2]);
    }
    return points;
  });
}
} // namespace

/** The field's interchange files: a DICOM Deformable Spatial Registration and Learn2Reg's .npz. */
void
BindInterchange(py::module_ & m)
{
  m.def("write_dicom_registration",
        [](const py::tuple & field, const std::string & fixed, const std::string & moving, const std::string & path) {
          const auto             image = ImportImage<itk::BiomechanicalFieldType>(field, "field");
          py::gil_scoped_release released;
          itk::WriteDeformableSpatialRegistration(image, fixed, moving, path);
        });
  m.def("read_dicom_registration", [](const std::string & path) {
    itk::DicomDeformableRegistration registration;
    {
      py::gil_scoped_release released;
      registration = itk::ReadDeformableSpatialRegistration(path);
    }
    py::dict frames;
    frames["registered_frame_of_reference_uid"] = registration.registeredFrameOfReferenceUID;
    frames["source_frame_of_reference_uid"] = registration.sourceFrameOfReferenceUID;
    return py::make_tuple(ToImage(ExportImage(registration.field.GetPointer())), frames);
  });
  m.def("write_field_npz", [](const py::tuple & field, const py::tuple & moving, const std::string & path) {
    const auto image = ImportImage<itk::BiomechanicalFieldType>(field, "field");
    auto       grid = itk::ImageBase<3>::New();
    itk::ApplyGridGeometry(grid.GetPointer(), GeometryOf(moving, "moving"));
    py::gil_scoped_release released;
    itk::WriteLearn2RegDisplacement(image, grid, path);
  });
}

void
BindClinical(py::module_ & m)
{
  BindMarkers(m);
  BindDose(m);
  BindStructureSets(m);
  BindInterchange(m);
}

} // namespace bmrpy
