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
#ifndef bmrPyModule_h
#define bmrPyModule_h

// The parts of the extension module _biomechreg: settings (bmrPySettings.cxx), results (bmrPyResults.cxx) and
// the functions (bmrPyModule.cxx).
#include "bmrScene.h"
#include "itkBiomechanicalPipelines.h"
#include "itkMarkerPipeline.h"

#include <pybind11/pybind11.h>

#include <memory>

namespace bmrpy {
namespace py = pybind11;

/** A registration's result with the settings it ran with (for writing it as biomechreg register does). */
struct Registration
{
  itk::RegistrationResult         result;
  itk::RegistrationSettings       settings;
  std::vector<itk::PipelineStage> stages;
};

/** A phantom pair with its settings (for writing it as biomechreg phantom does). */
struct Phantom
{
  itk::PhantomPair     pair;
  itk::PhantomSettings settings;
};

/** What markers() estimated, with its settings (for the report). */
struct Markers
{
  itk::MarkerResult   result;
  itk::MarkerSettings settings;
};

/** A forward simulation's result. */
struct Simulation
{
  itk::SimulationResult result;
};

/** EstimatorSettings, WallLoadSettings, UncertaintySettings, RegistrationSettings and PhantomSettings. */
void
BindSettings(py::module_ & m);

/** markers() and its MarkerSettings and Markers; dose(), conformal_plan(), read_landmarks() and their settings. */
void
BindClinical(py::module_ & m);

/** Scene, Registration, Phantom and Simulation. */
void
BindResults(py::module_ & m);

} // namespace bmrpy

#endif
