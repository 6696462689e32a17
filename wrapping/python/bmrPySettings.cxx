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
// The settings structs of the pipelines as Python classes: the C++ fields in snake_case, enumerations as the
// strings the command line takes ("rescan", "normal", ...).
#include "bmrPyModule.h"

#include <pybind11/stl.h>

#include <utility>
#include <vector>

namespace bmrpy {

namespace {
template<typename E>
using EnumNames = std::vector<std::pair<const char *, E>>;

/** A string property for the enumeration member \a member, one of \a names (else ValueError naming them). */
template<typename TClass, typename E>
void
DefEnum(py::class_<TClass> & cls, const char * name, E TClass::*member, EnumNames<E> names)
{
  cls.def_property(
    name,
    [member, names](const TClass & s) {
      for (const auto & [text, value] : names)
      {
        if (s.*member == value)
        {
          return std::string(text);
        }
      }
      return std::string("?");
    },
    [member, names, name](TClass & s, const std::string & text) {
      std::string known;
      for (const auto & [candidate, value] : names)
      {
        if (text == candidate)
        {
          s.*member = value;
          return;
        }
        known += std::string(known.empty() ? "" : ", ") + candidate;
      }
      throw py::value_error(std::string(name) + " must be one of " + known + ", got \"" + text + "\"");
    });
}

void
BindEstimatorSettings(py::module_ & m)
{
  py::class_<bmr::EstimatorSettings> e(
    m, "EstimatorSettings", "The estimator's stopping rules (bmr::EstimatorSettings).");
  e.def(py::init<>())
    .def_readwrite("number_of_sweep_samples", &bmr::EstimatorSettings::numberOfSweepSamples)
    .def_readwrite("maximum_inner_iterations", &bmr::EstimatorSettings::maximumInnerIterations)
    .def_readwrite("maximum_outer_iterations", &bmr::EstimatorSettings::maximumOuterIterations)
    .def_readwrite("outer_step_tolerance", &bmr::EstimatorSettings::outerStepTolerance)
    .def_readwrite("inner_gradient_tolerance", &bmr::EstimatorSettings::innerGradientTolerance)
    .def_readwrite("loose_inner_gradient_tolerance", &bmr::EstimatorSettings::looseInnerGradientTolerance)
    .def_readwrite("outer_gradient_tolerance", &bmr::EstimatorSettings::outerGradientTolerance)
    .def_readwrite("flatness_threshold", &bmr::EstimatorSettings::flatnessThreshold)
    .def_readwrite("uncertainty_step", &bmr::EstimatorSettings::uncertaintyStep)
    .def_readwrite("limit_element_inversion", &bmr::EstimatorSettings::limitElementInversion);

  py::class_<bmr::WallLoadSettings> w(
    m, "WallLoadSettings", "How the walls' unknown loads act (bmr::WallLoadSettings).");
  w.def(py::init<>())
    .def_readwrite("control_spacing", &bmr::WallLoadSettings::controlSpacing, "mm; 0: one control point per wall node")
    .def_readwrite("regularization", &bmr::WallLoadSettings::regularization);
  DefEnum(w,
          "motion",
          &bmr::WallLoadSettings::motion,
          EnumNames<bmr::WallMotionEnum>{ { "normal", bmr::WallMotionEnum::AlongNormals },
                                          { "free", bmr::WallMotionEnum::Free },
                                          { "traction", bmr::WallMotionEnum::NormalTraction },
                                          { "pressure", bmr::WallMotionEnum::UniformPressure } });
}

void
BindUncertaintySettings(py::module_ & m)
{
  using U = itk::UncertaintySettings;
  py::class_<U> u(m, "UncertaintySettings", "How the modulus' interval is stated (itk::UncertaintySettings).");
  u.def(py::init<>())
    .def_readwrite("resamples", &U::resamples)
    .def_readwrite("seed", &U::seed)
    .def_readwrite("threads", &U::threads, "resamples at once; 0: ITK's global default number of threads")
    .def_readwrite("simulation_mesh_scale", &U::simulationMeshScale)
    .def_readwrite("mesh_jitter", &U::meshJitter)
    .def_readwrite("shift_voxels", &U::shiftVoxels)
    .def_readwrite("rotation_degrees", &U::rotationDegrees)
    .def_readwrite("tangential_wall_fraction", &U::tangentialWallFraction)
    .def_readwrite("smoothing_voxels", &U::smoothingVoxels)
    .def_readwrite("correct_bias", &U::correctBias)
    .def_readwrite("warm_start", &U::warmStart)
    .def_readwrite("step_tolerance", &U::stepTolerance)
    .def_readwrite("stated_voxel_limit_mm", &U::statedVoxelLimitMM);
  DefEnum(u,
          "method",
          &U::method,
          EnumNames<itk::UncertaintyMethodEnum>{ { "rescan", itk::UncertaintyMethodEnum::Rescan },
                                                 { "bootstrap", itk::UncertaintyMethodEnum::Bootstrap },
                                                 { "curvature", itk::UncertaintyMethodEnum::Curvature },
                                                 { "none", itk::UncertaintyMethodEnum::None } });
  DefEnum(u,
          "quantiles",
          &U::quantiles,
          EnumNames<itk::IntervalQuantilesEnum>{ { "calibrated", itk::IntervalQuantilesEnum::Calibrated },
                                                 { "student", itk::IntervalQuantilesEnum::Student } });
}

void
BindRegistrationSettings(py::module_ & m)
{
  using R = itk::RegistrationSettings;
  py::class_<R> r(m,
                  "RegistrationSettings",
                  "Settings of register() (itk::RegistrationSettings); the defaults are biomechreg register's.");
  r.def(py::init<>())
    .def_readwrite("estimator", &R::estimator)
    .def_readwrite("walls", &R::walls)
    .def_readwrite("uncertainty", &R::uncertainty)
    .def_readwrite("coarse_factor", &R::coarseFactor)
    .def_readwrite("mesh_scale", &R::meshScale)
    .def_readwrite("push_field", &R::pushField)
    .def_readwrite("interpolate_slices", &R::interpolateSlices)
    .def_readwrite("element_state", &R::elementState)
    .def("validate",
         &R::Validate,
         "Raises ValueError naming the first setting out of its range (RegistrationSettings::Validate); "
         "register() does it too.");
}

void
BindPhantomSettings(py::module_ & m)
{
  using P = itk::PhantomSettings;
  py::class_<P> p(m, "PhantomSettings", "Settings of make_phantom() (itk::PhantomSettings).");
  p.def(py::init([](const std::string & anatomy) {
          if (anatomy != "pelvis" && anatomy != "spheres")
          {
            throw py::value_error("anatomy must be \"pelvis\" or \"spheres\", got \"" + anatomy + "\"");
          }
          return P::Defaults(anatomy == "pelvis" ? P::AnatomyEnum::Pelvis : P::AnatomyEnum::Spheres);
        }),
        py::arg("anatomy") = "pelvis")
    .def_property(
      "size",
      [](const P & s) { return s.grid.size; },
      [](P & s, const std::array<std::size_t, 3> & v) { s.grid.size = v; })
    .def_property(
      "spacing",
      [](const P & s) { return s.grid.spacing; },
      [](P & s, const std::array<double, 3> & v) { s.grid.spacing = v; })
    .def_property(
      "origin",
      [](const P & s) { return s.grid.origin; },
      [](P & s, const std::array<double, 3> & v) { s.grid.origin = v; })
    .def_property(
      "direction",
      [](const P & s) { return s.grid.direction; },
      [](P & s, const std::array<double, 9> & v) { s.grid.direction = v; })
    .def_readwrite("prostate_E", &P::prostateE, "kPa")
    .def_readwrite("prostate_nu", &P::prostateNu)
    .def_readwrite("tissue_E", &P::tissueE, "kPa")
    .def_readwrite("bladder_mm", &P::bladderMM)
    .def_readwrite("rectum_mm", &P::rectumMM)
    .def_readwrite("tumour_fraction", &P::tumourFraction)
    .def_readwrite("tumour_E", &P::tumourE, "kPa")
    .def_readwrite("bladder_kPa", &P::bladderKPa)
    .def_readwrite("rectum_kPa", &P::rectumKPa)
    .def_readwrite("noise_HU", &P::noiseHU)
    .def_readwrite("seed", &P::seed)
    .def_readwrite("number_of_seeds", &P::numberOfSeeds)
    .def_readwrite("tracking_noise_mm", &P::trackingNoiseMM)
    .def_readwrite("fractions", &P::fractions)
    .def_readwrite("contour_fractions", &P::contourFractions)
    .def_readwrite("truth_refinement", &P::truthRefinement)
    .def_readwrite("truth_refine_distance", &P::truthRefineDistance, "mm")
    .def_readwrite("truth_refine_size", &P::truthRefineSize, "mm")
    .def_readwrite("fixed_grid_shift_voxels", &P::fixedGridShiftVoxels);
  DefEnum(p,
          "model",
          &P::model,
          EnumNames<bmr::MaterialModelEnum>{ { "linear", bmr::MaterialModelEnum::Linear },
                                             { "neo_hookean", bmr::MaterialModelEnum::NeoHookean } });
  DefEnum(p,
          "wall_load",
          &P::filling,
          EnumNames<bmr::WallFillingEnum>{ { "normal", bmr::WallFillingEnum::AlongNormals },
                                           { "point", bmr::WallFillingEnum::FromPoint } });
  DefEnum(p,
          "truth_geometry",
          &P::truthGeometry,
          EnumNames<P::TruthGeometryEnum>{ { "anatomy", P::TruthGeometryEnum::Anatomy },
                                           { "voxels", P::TruthGeometryEnum::Voxels } });
}
} // namespace

void
BindSettings(py::module_ & m)
{
  BindEstimatorSettings(m);
  BindUncertaintySettings(m);
  BindRegistrationSettings(m);
  BindPhantomSettings(m);
}

} // namespace bmrpy
