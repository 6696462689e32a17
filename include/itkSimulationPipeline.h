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
#ifndef itkSimulationPipeline_h
#define itkSimulationPipeline_h

#include "bmrSimulation.h"
#include "itkPipelineTypes.h"

#include <vector>

namespace itk {

// Forward simulation of a scene: SimulateLabelImage(), SimulateMesh().

/** What SimulateLabelImage() made. \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
struct BiomechanicalRegistration_EXPORT SimulationResult
{
  bmr::TetrahedralMesh            mesh;                  ///< with displacement [mm] and force [mN]
  bmr::ForwardSimulation          simulation;            ///< per-node and per-element fields of the solution
  BiomechanicalFieldType::Pointer pullBack;              ///< fixed -> moving [mm] on the reference grid
  BiomechanicalFieldType::Pointer push;                  ///< moving -> fixed [mm] on the moving grid (if asked for)
  SizeValueType                   invertedElements{ 0 }; ///< elements the displacement inverts
  std::vector<std::string>        warnings;
  std::vector<PipelineStage>      stages;
};

/** Meshes \a movingLabels for \a scene (CGAL Mesh_3), solves the scene's forward problem and computes the
 * pull-back field on \a reference's grid (and the push field on the moving grid when \a pushField).
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
BiomechanicalRegistration_EXPORT SimulationResult
SimulateLabelImage(const BiomechanicalLabelImageType * movingLabels,
                   const bmr::Scene &                  scene,
                   const ImageBase<3> *                reference,
                   PipelineObserver *                  observer = nullptr,
                   bool                                pushField = true);

/** As SimulateLabelImage() on a mesh already made for \a scene (its labels, sizes and excluded labels): the forward
 * problem and the fields, the push field on \a movingReference's grid. \ingroup BiomechanicalRegistrationPipelines */
BiomechanicalRegistration_EXPORT SimulationResult
SimulateMesh(bmr::TetrahedralMesh mesh,
             const bmr::Scene &   scene,
             const ImageBase<3> * reference,
             const ImageBase<3> * movingReference,
             PipelineObserver *   observer = nullptr,
             bool                 pushField = true);

} // namespace itk

#endif
