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
#ifndef itkWallBasisTraining_h
#define itkWallBasisTraining_h

#include "bmrWallMotionBasis.h"
#include "itkRegistrationPipeline.h"

namespace itk {

/** \brief A basis of wall motion trained from one patient's scans (dissertation section 5.3.2.2, one source surface
 * and several targets), for RegistrationSettings::walls.trainedBasis (`biomechreg register --wall-basis`).
 *
 * The moving labels are meshed as RegisterSegmentedPair() meshes them (the scene's sizes times settings.meshScale, the
 * same mesher seeds, interpolated between thick slices when settings.interpolateSlices), and the atlas is that mesh's
 * loaded walls (bmr::WallAtlas()). Each fixed label image gives one example: the walls' nodes matched to its organs
 * by the surface matching that starts an estimation (bmr::EstimationObjective::MatchDisplacement(), walls free to
 * move in any direction). The basis is the examples' PCA (bmr::TrainWallMotionBasis(), at most \a maximumModes
 * modes); \a training says what it was trained on (the file names, say).
 *
 * A registration of the same moving labels with the same scene and mesh settings meshes the same walls, so the basis
 * applies to it exactly (bmr::TrainedWallLoads::GetTransferDistances() all 0); another mesh of the walls takes it by
 * projection onto the atlas. Throws itk::ExceptionObject for fewer than two fixed images, images that do not overlap
 * the moving one, or invalid settings.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines
 */
BiomechanicalRegistration_EXPORT bmr::WallMotionBasis
                                 TrainWallBasis(const BiomechanicalLabelImageType *                      movingLabels,
                                                const std::vector<const BiomechanicalLabelImageType *> & fixedLabels,
                                                const bmr::Scene &                                       scene,
                                                const RegistrationSettings &                             settings,
                                                std::size_t                                              maximumModes,
                                                const std::string &                                      training);

} // namespace itk

#endif
