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
#ifndef bmrSimulation_h
#define bmrSimulation_h

#include "bmrForwardModel.h"
#include "bmrNeoHookeanForwardModel.h"
#include "bmrLinearElasticModel.h"
#include "bmrScene.h"

#include <functional>

namespace bmr {

/** \brief Builds the FEM mesh a scene needs from a moving label volume.
 *
 * Labels with the role outside are mapped to background; when the scene sets a
 * region-of-interest margin the volume is cropped to the bounding box of the
 * non-material labels (hollow, fixed, unknown material) grown by the margin, so
 * that tissue far from the organs is not meshed. The volume is meshed with CGAL
 * (every non-zero label, excluded ones with a coarse size since only their
 * surface matters), then the excluded elements (fixed, hollow) are removed and
 * their walls recorded as boundary faces carrying their label.
 * Throws when a label the scene simulates did not survive meshing. */
BiomechanicalRegistration_EXPORT TetrahedralMesh
MeshSceneLabels(const std::int32_t * labels, const GridGeometry & grid, const Scene & scene);

/** As MeshSceneLabels(), but the surfaces are those of \a labelAt (physical mm -> label), the anatomy that
 * \a labels voxelizes on \a grid (MeshImplicitLabelsOnGrid()): the region of interest, the roles and the
 * mesh sizes come from the voxels as there, the geometry from the function. Used for the phantom's truth, whose
 * surfaces must not move with its mesh sizes. */
BiomechanicalRegistration_EXPORT TetrahedralMesh
MeshSceneFunction(const std::function<std::int32_t(double, double, double)> & labelAt,
                  const std::int32_t *                                        labels,
                  const GridGeometry &                                        grid,
                  const Scene &                                               scene);

/** Elements across a simulated label (bmr::LabelResolution) below which MeshResolutionWarnings() warns. */
constexpr double MinimumElementsAcross = 2.0;

/** Warnings, one per simulated label (material or unknown material) of \a scene that \a mesh resolves
 * with fewer than MinimumElementsAcross elements across (bmr::ComputeLabelResolution), naming the label:
 * linear tetrahedra cannot bend through a layer one element thick, and the solution stiffens (the errors
 * on the two-layer sphere behind the limit: docs/history/benchmarks.md, "Extreme cases"). */
BiomechanicalRegistration_EXPORT std::vector<std::string>
                                 MeshResolutionWarnings(const Scene & scene, const TetrahedralMesh & mesh);

/** Materials of the simulated labels (E [kPa], nu). */
BiomechanicalRegistration_EXPORT std::map<std::int32_t, MaterialParameters>
                                 SceneMaterials(const Scene & scene);

/** Boundary conditions of a forward simulation of a scene on its mesh: u = 0 on
 * the walls of fixed labels (and on the outer boundary when the region of
 * interest's boundary is fixed), the loads' prescribed wall displacements [mm]
 * and pressure forces [mN]. A node on a fixed wall stays fixed. */
struct BiomechanicalRegistration_EXPORT BoundaryConditions
{
  std::vector<std::int32_t> dirichletNodes;
  std::vector<double>       dirichletValues; ///< 3 per Dirichlet node [mm]
  std::vector<double>       forces;          ///< 3N [mN]
};

BiomechanicalRegistration_EXPORT BoundaryConditions
SceneBoundaryConditions(const Scene & scene, const TetrahedralMesh & mesh);

/** Result of a forward simulation: nodal displacement [mm], total nodal force
 * (applied + reaction) [mN], Dirichlet flag per node, von Mises stress [kPa],
 * E [kPa] and nu per element, and the solver's timings. */
struct BiomechanicalRegistration_EXPORT ForwardSimulation
{
  std::vector<double>        displacement;
  std::vector<double>        force;
  std::vector<unsigned char> dirichlet;
  std::vector<double>        vonMises;
  std::vector<double>        youngsModulus;
  std::vector<double>        poissonRatio;
  SolverTimings              timings;               ///< neo-Hookean: the whole Newton solve counts as "solve"
  unsigned int               newtonIterations{ 0 }; ///< neo-Hookean only (0 for the linear model)
  unsigned int               loadIncrements{ 0 };   ///< neo-Hookean only: accepted load increments
  unsigned int               factorizations{ 0 };   ///< neo-Hookean only: numeric Cholesky factorizations
};

/** The forward model of the scene's tissue model (Scene::model: LinearForwardModel or
 * NeoHookeanForwardModel) on \a mesh, which must outlive it, with \a materials (SceneMaterials() or
 * estimated moduli); \a newton: the neo-Hookean model's Newton settings. */
BiomechanicalRegistration_EXPORT std::unique_ptr<ForwardModel>
                                 MakeForwardModel(const Scene &                                      scene,
                                                  const TetrahedralMesh &                            mesh,
                                                  const std::map<std::int32_t, MaterialParameters> & materials,
                                                  const NewtonSettings &                             newton = NewtonSettings{});

/** Von Mises stress [kPa] of every element in the state \a u [mm] under the scene's model: of the linear
 * stress, or of the Cauchy stress of the neo-Hookean model. */
BiomechanicalRegistration_EXPORT std::vector<double>
                                 SceneVonMisesStress(const Scene &                                      scene,
                                                     const TetrahedralMesh &                            mesh,
                                                     const std::map<std::int32_t, MaterialParameters> & materials,
                                                     const std::vector<double> &                        u);

/** The prescribed displacements of \a bc as a full nodal vector (3N [mm], zero off the Dirichlet nodes). */
BiomechanicalRegistration_EXPORT std::vector<double>
                                 PrescribedDisplacements(const BoundaryConditions & bc, std::size_t numberOfNodes);

/** Fills the per-element E [kPa] and nu of \a simulation from \a materials. */
BiomechanicalRegistration_EXPORT void
SetElementMaterials(const TetrahedralMesh &                            mesh,
                    const std::map<std::int32_t, MaterialParameters> & materials,
                    ForwardSimulation &                                simulation);

/** Solves the scene's forward problem on \a mesh (made by MeshSceneLabels) with the scene's model; the linear
 * model factorizes and solves on \a threads threads (LinearElasticModel::SetNumberOfSolveThreads; the
 * displacements are the same bit for bit whatever the number). */
BiomechanicalRegistration_EXPORT ForwardSimulation
SimulateScene(const Scene & scene, const TetrahedralMesh & mesh, unsigned threads = 1);

} // namespace bmr

#endif
