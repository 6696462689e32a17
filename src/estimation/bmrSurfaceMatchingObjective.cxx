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
#include "bmrSurfaceMatchingObjective.h"

#include "bmrError.h"
#include "bmrSimulation.h"
#include "bmrTrainedWallLoads.h"

namespace bmr {
namespace {
/** Nodes of the wall of an excluded label, or of the surface of a simulated one. Outside labels are
 * mapped to 0 before meshing: their wall is the outer boundary. */
std::vector<std::int32_t>
SurfaceNodes(const TetrahedralMesh & mesh, const SceneLabel & label)
{
  const bool simulated = label.role == LabelRoleEnum::Material || label.role == LabelRoleEnum::UnknownMaterial;
  if (simulated)
  {
    return NodesOnLabelSurface(mesh, label.value);
  }
  return NodesOnBoundary(mesh, label.role == LabelRoleEnum::Outside ? 0 : label.value);
}

std::vector<std::int32_t>
UnknownLabelValues(const Scene & scene)
{
  std::vector<std::int32_t> values;
  for (const SceneLabel * l : scene.UnknownLabels())
  {
    values.push_back(l->value);
  }
  return values;
}

std::vector<const DataTerm *>
Terms(const std::unique_ptr<SurfaceDistanceTerm> & term)
{
  return { term.get() };
}
} // namespace

std::vector<ObjectiveSurface>
SceneObjectiveSurfaces(const Scene &                                                                scene,
                       const TetrahedralMesh &                                                      mesh,
                       const std::map<std::int32_t, std::shared_ptr<const SignedDistanceSampler>> & maps)
{
  std::vector<ObjectiveSurface> surfaces;
  for (const ObjectiveTerm & term : scene.objective)
  {
    const SceneLabel * label = scene.FindLabel(term.label);
    if (label == nullptr)
    {
      Fail("SceneObjectiveSurfaces", "objective label \"" + term.label + "\" is not defined in the scene");
    }
    const auto map = maps.find(label->value);
    if (map == maps.end() || !map->second)
    {
      Fail("SceneObjectiveSurfaces", "no distance map was given for objective label \"" + term.label + "\"");
    }
    ObjectiveSurface s;
    s.name = term.label;
    s.label = label->value;
    s.weight = term.weight;
    s.nodes = SurfaceNodes(mesh, *label);
    s.distance = map->second;
    if (s.nodes.empty())
    {
      Fail("SceneObjectiveSurfaces", "objective label \"" + term.label + "\" has no surface node in the mesh");
    }
    surfaces.push_back(std::move(s));
  }
  return surfaces;
}

std::vector<LoadedWall>
SceneLoadedWalls(const Scene & scene, const TetrahedralMesh & mesh)
{
  std::vector<LoadedWall> walls;
  for (const std::string & name : scene.forceSurfaces)
  {
    const SceneLabel * label = scene.FindLabel(name);
    if (label == nullptr)
    {
      Fail("SceneLoadedWalls", "force surface \"" + name + "\" is not defined in the scene");
    }
    walls.push_back({ name, SurfaceNodes(mesh, *label), label->role == LabelRoleEnum::Outside ? 0 : label->value });
  }
  return walls;
}

namespace detail {
SceneObjectiveParts::SceneObjectiveParts(const TetrahedralMesh &       mesh,
                                         const Scene &                 scene,
                                         std::vector<ObjectiveSurface> surfaces,
                                         const WallLoadSettings *      trained)
{
  surfaceDistance.reset(new SurfaceDistanceTerm(mesh, std::move(surfaces)));
  BoundaryConditions bc = SceneBoundaryConditions(scene, mesh);
  if (trained != nullptr)
  {
    if (trained->trainedBasis == nullptr)
    {
      FailInput("SurfaceMatchingObjective", "the wall settings given for a trained basis have none");
    }
    trained->Validate();
    trainedLoads.reset(new TrainedWallLoads(mesh,
                                            bc.dirichletNodes,
                                            bc.dirichletValues,
                                            std::move(bc.forces),
                                            SceneLoadedWalls(scene, mesh),
                                            *trained->trainedBasis,
                                            trained->basisModes,
                                            trained->basisPriorWeight));
  }
  else
  {
    loads.reset(
      new WallLoads(mesh, bc.dirichletNodes, bc.dirichletValues, std::move(bc.forces), SceneLoadedWalls(scene, mesh)));
  }
  const SceneLabel * gauge = scene.GaugeLabel();
  if (loads && gauge)
  {
    // The tissue around the walls: the scale that makes a normal traction's parameter read as mm of wall motion.
    loads->SetTractionShearModulus(gauge->youngsModulus / (2.0 * (1.0 + gauge->poissonRatio)));
  }
  NewtonSettings newton;
  newton.restartFromRest = false; // a trial point whose warm path fails is infeasible
  model = MakeForwardModel(scene, mesh, SceneMaterials(scene), newton);
}

WallLoads &
SceneObjectiveParts::Walls(const char * caller) const
{
  if (!loads)
  {
    Fail(caller, "the walls move in a trained basis (TrainedWallLoads), not in WallLoads");
  }
  return *loads;
}
} // namespace detail

SurfaceMatchingObjective::SurfaceMatchingObjective(const TetrahedralMesh &       mesh,
                                                   const Scene &                 scene,
                                                   std::vector<ObjectiveSurface> surfaces)
  : detail::SceneObjectiveParts(mesh, scene, std::move(surfaces), nullptr)
  , EstimationObjective(*model, ActiveLoads(), Terms(surfaceDistance), UnknownLabelValues(scene))
{}

SurfaceMatchingObjective::SurfaceMatchingObjective(const TetrahedralMesh &       mesh,
                                                   const Scene &                 scene,
                                                   std::vector<ObjectiveSurface> surfaces,
                                                   const WallLoadSettings &      trained)
  : detail::SceneObjectiveParts(mesh, scene, std::move(surfaces), &trained)
  , EstimationObjective(*model, ActiveLoads(), Terms(surfaceDistance), UnknownLabelValues(scene))
{}

void
SurfaceMatchingObjective::SetWallControlSpacing(double spacing)
{
  Walls("SurfaceMatchingObjective::SetWallControlSpacing").SetControlSpacing(spacing);
}

void
SurfaceMatchingObjective::SetWallRegularization(double alpha)
{
  Walls("SurfaceMatchingObjective::SetWallRegularization").SetRegularization(alpha);
}

void
SurfaceMatchingObjective::SetWallMotionAlongNormals(bool normal)
{
  SetWallMotion(normal ? WallMotionEnum::AlongNormals : WallMotionEnum::Free);
}

void
SurfaceMatchingObjective::SetWallMotion(WallMotionEnum motion)
{
  WallLoads & walls = Walls("SurfaceMatchingObjective::SetWallMotion");
  walls.SetMotion(motion);
  model->SetConstrainedNodes(walls.GetConstrainedNodes());
}

} // namespace bmr
