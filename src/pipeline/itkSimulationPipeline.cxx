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
// The forward pipeline: label map -> mesh -> FEM -> displacement fields.
#include "itkPipelineStages.h"

#include "bmrTaskTrace.h"
#include "itkLabelImageToTetrahedralMeshFilter.h"
#include "itkPhysicsDeformationFieldSource.h"
#include "itkMultiThreaderBase.h"

#include <cmath>
#include <iomanip>
#include <sstream>

namespace itk {
namespace pipeline {

void
StageClock::Begin(const std::string & name)
{
  m_Current = name;
  if (m_Observer)
  {
    m_Observer->StageBegin(name);
  }
  m_Start = bmr::SteadyClock::now();
}

void
StageClock::End(const std::string & detail)
{
  const double seconds = bmr::SecondsSince(m_Start);
  m_Stages.push_back({ m_Current, seconds });
  if (m_Observer)
  {
    m_Observer->StageEnd(m_Current, seconds, detail);
  }
}

void
StageClock::Warn(std::vector<std::string> & list, const std::vector<std::string> & warnings)
{
  for (const std::string & w : warnings)
  {
    list.push_back(w);
    if (m_Observer)
    {
      m_Observer->Warning(w);
    }
  }
}

bmr::TetrahedralMesh
MeshLabelImage(const BiomechanicalLabelImageType * labels,
               const bmr::Scene &                  scene,
               StageClock &                        clock,
               const std::string &                 stage)
{
  clock.Begin(stage);
  auto mesher = LabelImageToTetrahedralMeshFilter<BiomechanicalLabelImageType>::New();
  mesher->SetInput(labels);
  mesher->SetScene(scene);
  mesher->Update();
  bmr::TetrahedralMesh   mesh = mesher->GetOutput()->Get();
  const bmr::MeshQuality q = mesher->GetMeshQuality();
  std::ostringstream     detail;
  detail << mesh.GetNumberOfTetrahedra() << " tetrahedra, " << mesh.GetNumberOfPoints() << " nodes, min dihedral "
         << std::setprecision(1) << q.minimumDihedralAngleDegrees << " deg";
  clock.End(detail.str());
  return mesh;
}

namespace {
/** Keeps the detail of the stage that ended last: a background stage tells it later, on the caller's thread. */
struct RecordingObserver : PipelineObserver
{
  std::string detail;
  void
  StageEnd(const std::string &, double, const std::string & stageDetail) override
  {
    detail = stageDetail;
  }
};
} // namespace

BackgroundMesh::BackgroundMesh(const BiomechanicalLabelImageType * labels, const bmr::Scene & scene)
  : m_Labels(labels)
  , m_Scene(scene)
{
  m_Task = std::make_unique<bmr::BackgroundTask>("fine mesh alongside",
                                                 MultiThreaderBase::GetGlobalDefaultNumberOfThreads() > 1,
                                                 [this]() { m_Made = Make(m_Labels, m_Scene); });
  if (!m_Task->Alongside())
  {
    m_Task.reset(); // Take() meshes, as a stage of its own
  }
}

BackgroundMesh::~BackgroundMesh() = default; // a mesh under way is waited for, its exception dropped

auto
BackgroundMesh::Make(const BiomechanicalLabelImageType * labels, const bmr::Scene & scene) -> Made
{
  std::vector<PipelineStage> stages;
  RecordingObserver          recorder;
  StageClock                 quiet(&recorder, stages);
  Made                       made;
  made.mesh = MeshLabelImage(labels, scene, quiet, "mesh");
  made.detail = recorder.detail;
  made.seconds = stages.back().seconds;
  return made;
}

bmr::TetrahedralMesh
BackgroundMesh::Take(StageClock & clock, const std::string & stage)
{
  if (!Alongside())
  {
    return MeshLabelImage(m_Labels, m_Scene, clock, stage);
  }
  clock.Begin(stage);
  std::string          detail;
  bmr::TetrahedralMesh mesh = TakeAlongside(detail);
  clock.End(detail + " (meshed alongside: " + bmr::SecondsText(m_Seconds) + " s, this stage the wait)");
  return mesh;
}

bmr::TetrahedralMesh
BackgroundMesh::TakeAlongside(std::string & detail)
{
  const std::unique_ptr<bmr::BackgroundTask> task = std::move(m_Task);
  task->Wait();
  detail = m_Made.detail;
  m_Seconds = m_Made.seconds;
  return std::move(m_Made.mesh);
}

void
ComputeFields(SimulationResult &   result,
              const ImageBase<3> * fixedReference,
              const ImageBase<3> * movingReference,
              bool                 pushField,
              const bmr::Scene &   scene,
              StageClock &         clock)
{
  using SourceType = PhysicsDeformationFieldSource<BiomechanicalFieldType>;
  std::map<std::int32_t, std::string> names;
  for (const bmr::SceneLabel & l : scene.labels)
  {
    names[l.value] = l.name;
  }
  auto meshObject = TetrahedralMeshObject::New();
  meshObject->Set(result.mesh);
  clock.Begin("pull-back field (fixed -> moving)");
  auto pull = SourceType::New();
  pull->SetMesh(meshObject);
  pull->SetReferenceImage(fixedReference);
  pull->SetLabelNames(names);
  pull->Update();
  result.pullBack = pull->GetOutput();
  result.invertedElements = pull->GetNumberOfInvertedElements();
  clock.End();
  if (!pushField)
  {
    return;
  }
  clock.Begin("push field (moving -> fixed)");
  auto push = SourceType::New();
  push->SetMesh(meshObject);
  push->SetReferenceImage(movingReference);
  push->SetFieldDirection(SourceType::FieldDirectionEnum::MovingToFixed);
  push->Update();
  result.push = push->GetOutput();
  clock.End();
}

} // namespace pipeline

bmr::Scene
ScaledMeshSizes(bmr::Scene scene, double factor)
{
  scene.mesh.cellSize *= factor;
  scene.mesh.facetSize *= factor;
  scene.mesh.facetDistance *= factor;
  scene.mesh.refineSize *= factor; // a size; its distance is the anatomy's, not scaled
  for (const auto & keyAndSizes : scene.mesh.SizesPerLabel())
  {
    for (auto & kv : *keyAndSizes.second)
    {
      kv.second *= factor;
    }
  }
  return scene;
}

SimulationResult
SimulateLabelImage(const BiomechanicalLabelImageType * movingLabels,
                   const bmr::Scene &                  scene,
                   const ImageBase<3> *                reference,
                   PipelineObserver *                  observer,
                   bool                                pushField)
{
  std::vector<PipelineStage> stages;
  pipeline::StageClock       clock(observer, stages);
  SimulationResult out = SimulateMesh(pipeline::MeshLabelImage(movingLabels, scene, clock, "mesh (CGAL Mesh_3)"),
                                      scene,
                                      reference,
                                      movingLabels,
                                      observer,
                                      pushField);
  out.stages.insert(out.stages.begin(), stages.begin(), stages.end());
  return out;
}

SimulationResult
SimulateMesh(bmr::TetrahedralMesh mesh,
             const bmr::Scene &   scene,
             const ImageBase<3> * reference,
             const ImageBase<3> * movingReference,
             PipelineObserver *   observer,
             bool                 pushField)
{
  SimulationResult     out;
  pipeline::StageClock clock(observer, out.stages);
  out.mesh = std::move(mesh);
  clock.Warn(out.warnings, scene.Warnings());
  clock.Warn(out.warnings, bmr::MeshResolutionWarnings(scene, out.mesh));

  clock.Begin("FEM (assemble, factorize, solve)");
  out.simulation = bmr::SimulateScene(scene, out.mesh, MultiThreaderBase::GetGlobalDefaultNumberOfThreads());
  out.mesh.displacement = out.simulation.displacement;
  out.mesh.force = out.simulation.force;
  double umax = 0.0;
  for (std::size_t n = 0; n < out.mesh.GetNumberOfPoints(); ++n)
  {
    const double * u = &out.mesh.displacement[3 * n];
    umax = std::max(umax, std::hypot(u[0], u[1], u[2]));
  }
  std::ostringstream fem;
  fem << "max |u| " << std::setprecision(2) << umax << " mm";
  if (scene.model == bmr::MaterialModelEnum::NeoHookean)
  {
    fem << ", neo-Hookean: " << out.simulation.newtonIterations << " Newton iterations in "
        << out.simulation.loadIncrements << " load increments, " << out.simulation.factorizations << " factorizations";
  }
  clock.End(fem.str());
  // The FEM stage in the solver's own parts.
  out.stages.pop_back();
  const bmr::SolverTimings & t = out.simulation.timings;
  clock.Add("assemble", t.assemble);
  clock.Add("factorize", t.analyze + t.factorize);
  clock.Add("solve", t.solve);
  pipeline::ComputeFields(out, reference, movingReference, pushField, scene, clock);
  return out;
}

} // namespace itk
