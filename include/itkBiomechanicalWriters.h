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
#ifndef itkBiomechanicalWriters_h
#define itkBiomechanicalWriters_h

#include "itkBiomechanicalPipelines.h"

namespace itk {

/** Creates \a path and its missing parents (like mkdir -p); throws naming it when it cannot.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationIO */
BiomechanicalRegistration_EXPORT void
MakeOutputDirectory(const std::string & path);

/** mesh.vtu of a simulated or estimated state: displacement [mm], force [mN], Dirichlet flags per node;
 * label, E [kPa], nu, von Mises stress [kPa] per element (ParaView). \ingroup BiomechanicalRegistration
 * BiomechanicalRegistrationIO */
BiomechanicalRegistration_EXPORT void
WriteSimulationMesh(const std::string & path, const SimulationResult & result);

/** Writes into \a directory (created when missing): mesh.vtu, field.nrrd (fixed -> moving [mm]),
 * forward_field.nrrd (when computed), warped_labels.nrrd and warped_ct.nrrd (when given); every file through
 * a temporary name. \ingroup BiomechanicalRegistration BiomechanicalRegistrationIO */
BiomechanicalRegistration_EXPORT void
WriteSimulationOutputs(const std::string &                 directory,
                       const SimulationResult &            result,
                       const BiomechanicalLabelImageType * warpedLabels,
                       const BiomechanicalCTImageType *    warpedCT);

/** Writes a registration into \a directory: WriteSimulationOutputs(), history.csv (every fine-mesh inner solve,
 * then the accepted outer iterates), sweep.csv and report.json, whose wall times are \a stages and the
 * writing itself. Returns the writing's stage ("write outputs"). \ingroup BiomechanicalRegistration
 * BiomechanicalRegistrationIO */
BiomechanicalRegistration_EXPORT PipelineStage
WriteRegistrationOutputs(const std::string &                directory,
                         const RegistrationResult &         result,
                         const RegistrationSettings &       settings,
                         const std::vector<PipelineStage> & stages);

/** Writes a phantom pair into \a directory: moving and fixed CT and labels, truth_field.nrrd, scene.json (what
 * the estimator sees), truth_scene.json, truth.json and the seed landmarks. \ingroup BiomechanicalRegistration
 * BiomechanicalRegistrationIO */
BiomechanicalRegistration_EXPORT void
WritePhantomPair(const std::string & directory, const PhantomPair & pair, const PhantomSettings & settings);

} // namespace itk

#endif
