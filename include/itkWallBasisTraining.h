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

/** One patient of a wall basis's training: the planning scan's labels and the daily scans' (one example each). */
struct WallBasisTrainingPatient
{
  const BiomechanicalLabelImageType *              movingLabels{ nullptr };
  std::vector<const BiomechanicalLabelImageType *> fixedLabels;
};

/** \brief A basis of wall motion trained from patients' scans (dissertation sections 5.3.2.2-5.3.2.3), for
 * RegistrationSettings::walls.trainedBasis (`biomechreg register --wall-basis`).
 *
 * The moving labels are meshed as RegisterSegmentedPair() meshes them (the scene's sizes times settings.meshScale, the
 * same mesher seeds, interpolated between thick slices when settings.interpolateSlices), and the atlas is that mesh's
 * loaded walls (bmr::WallAtlas()). Each fixed label image gives one example: the walls' nodes matched to its organs
 * by the surface matching that starts an estimation (bmr::EstimationObjective::MatchDisplacement(), walls free to
 * move in any direction). The basis is the examples' PCA (bmr::TrainWallMotionBasis(), at most \a maximumModes
 * modes); \a training says what it was trained on (the file names, say).
 *
 * With several patients the first one's walls are the atlas; every other patient's walls are meshed the same way, the
 * atlas fitted to them (bmr::FitAtlasToWalls(): the correspondence), and each of their examples taken at the fitted
 * atlas's points. A registration of the first patient's moving labels with the same scene and mesh settings meshes
 * the same walls, so the basis applies to it exactly (bmr::TrainedWallLoads::GetTransferDistances() all 0); another
 * patient's walls take it through the atlas fitted to them. Throws itk::ExceptionObject for fewer than two examples
 * in all, images that do not overlap their moving one, or invalid settings.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines
 */
BiomechanicalRegistration_EXPORT bmr::WallMotionBasis
                                 TrainWallBasis(const std::vector<WallBasisTrainingPatient> & patients,
                                                const bmr::Scene &                            scene,
                                                const RegistrationSettings &                  settings,
                                                std::size_t                                   maximumModes,
                                                const std::string &                           training);
/** One patient's scans (TrainWallBasis() above). */
BiomechanicalRegistration_EXPORT bmr::WallMotionBasis
                                 TrainWallBasis(const BiomechanicalLabelImageType *                      movingLabels,
                                                const std::vector<const BiomechanicalLabelImageType *> & fixedLabels,
                                                const bmr::Scene &                                       scene,
                                                const RegistrationSettings &                             settings,
                                                std::size_t                                              maximumModes,
                                                const std::string &                                      training);

} // namespace itk

#endif
