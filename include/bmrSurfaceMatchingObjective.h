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
#ifndef bmrSurfaceMatchingObjective_h
#define bmrSurfaceMatchingObjective_h

#include "bmrEstimationObjective.h"
#include "bmrScene.h"

#include <memory>

namespace bmr {

/** The objective surfaces of \a scene on \a mesh: for a simulated organ the nodes of its label surface,
 * for a hollow, fixed or outside label the nodes of its wall. \a maps gives the distance map of every
 * objective label (by value). Throws when a map is missing or a surface has no node. */
BiomechanicalRegistration_EXPORT std::vector<ObjectiveSurface>
                                 SceneObjectiveSurfaces(const Scene &                                                                scene,
                                                        const TetrahedralMesh &                                                      mesh,
                                                        const std::map<std::int32_t, std::shared_ptr<const SignedDistanceSampler>> & maps);

/** The loaded walls of the scene's force surfaces on \a mesh (wall nodes, face label for the normals).
 * Throws when a force surface is not defined. */
BiomechanicalRegistration_EXPORT std::vector<LoadedWall>
                                 SceneLoadedWalls(const Scene & scene, const TetrahedralMesh & mesh);

namespace detail {
/** The parts SurfaceMatchingObjective owns, built before the objective that references them. */
struct BiomechanicalRegistration_EXPORT SceneObjectiveParts
{
  /** With \a trained (a WallLoadSettings with a trained basis) the walls' loads are TrainedWallLoads, else WallLoads.
   */
  SceneObjectiveParts(const TetrahedralMesh &       mesh,
                      const Scene &                 scene,
                      std::vector<ObjectiveSurface> surfaces,
                      const WallLoadSettings *      trained);
  std::unique_ptr<ForwardModel>         model;
  std::unique_ptr<WallLoads>            loads; ///< null with a trained basis
  std::unique_ptr<LoadParameterization> trainedLoads;
  std::unique_ptr<SurfaceDistanceTerm>  surfaceDistance;

  LoadParameterization &
  ActiveLoads()
  {
    return trainedLoads ? *trainedLoads : static_cast<LoadParameterization &>(*loads);
  }
  /** The WallLoads, or a refusal naming \a caller with a trained basis. */
  WallLoads &
  Walls(const char * caller) const;
};
} // namespace detail

/** \brief The registration objective of a scene (dissertation chapter 3): the tissue model of the scene
 * (Scene::model: LinearForwardModel or NeoHookeanForwardModel) with its materials, the wall displacements of its force
 * surfaces as the unknown loads (WallLoads; u = 0 on fixed walls) and the surface distance of its objective surfaces
 * (SurfaceDistanceTerm), composed by EstimationObjective.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationEstimation
 */
class BiomechanicalRegistration_EXPORT SurfaceMatchingObjective
  : private detail::SceneObjectiveParts
  , public EstimationObjective
{
public:
  /** \a mesh must outlive the objective. Throws when the scene has nothing to estimate (no unknown
   * modulus and no force surface), a force surface has no free wall node in the mesh, or the objective
   * is empty. */
  SurfaceMatchingObjective(const TetrahedralMesh & mesh, const Scene & scene, std::vector<ObjectiveSurface> surfaces);
  /** As above, the walls moving in the trained basis of \a trained (WallLoadSettings::trainedBasis, which must be set,
   * with its basisModes and basisPriorWeight): TrainedWallLoads instead of WallLoads, whose setters below then
   * throw. */
  SurfaceMatchingObjective(const TetrahedralMesh &       mesh,
                           const Scene &                 scene,
                           std::vector<ObjectiveSurface> surfaces,
                           const WallLoadSettings &      trained);

  /** WallLoads::SetControlSpacing() [mm]. */
  void
  SetWallControlSpacing(double spacing);
  /** WallLoads::SetRegularization(). */
  void
  SetWallRegularization(double alpha);
  /** WallLoads::SetMotion(): along the normals (true, default) or free. */
  void
  SetWallMotionAlongNormals(bool normal);
  /** WallLoads::SetMotion(), and the forward model's constrained nodes with it (NormalTraction frees the walls;
   * its traction scale takes the shear modulus of the scene's gauge label). */
  void
  SetWallMotion(WallMotionEnum motion);
  /** The initial wall parameters by surface matching (EstimateInitialParameters()). */
  std::vector<double>
  MatchSurfaces() const
  {
    return EstimateInitialParameters();
  }
  /** |phi| statistics of the deformed surface nodes [mm]. */
  std::vector<ResidualStatistics>
  ComputeSurfaceDistances(const std::vector<double> & u) const
  {
    return ComputeStatistics(u);
  }
  /** The wall loads (control nodes, normals); throws with a trained basis. */
  const WallLoads &
  GetWallLoads() const
  {
    return Walls("SurfaceMatchingObjective::GetWallLoads");
  }
};

} // namespace bmr

#endif
