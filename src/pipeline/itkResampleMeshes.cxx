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
// The resamples' fine meshes: their scenes and the prefetch that makes them while the fit runs.
#include "itkPipelineStages.h"

#include "bmrParallel.h"
#include "bmrTaskTrace.h"

#include <exception>
#include <string>
#include <vector>

namespace itk {
namespace pipeline {

bmr::Scene
ResampleMeshScene(const bmr::Scene & scene, const UncertaintySettings & u, unsigned int k)
{
  std::mt19937_64 rng = ResampleRandom(u, k, ResampleDraw::MeshSizes);
  return ScaledMeshSizes(scene, Uniform(rng, 1.0 - u.meshJitter, 1.0 + u.meshJitter));
}

ResampleMeshPrefetch::ResampleMeshPrefetch(const BiomechanicalLabelImageType * movingLabels,
                                           const bmr::Scene &                  scene,
                                           const UncertaintySettings &         u)
  : m_Meshes(u.resamples)
  // Beside the fit, which keeps two cores busy at most: the meshes side by side on the rest of the budget (one
  // after the other on a small machine); each resample's mesh is drawn from its own random stream.
  , m_Task("resample meshes alongside", true, [this, movingLabels, scene, u]() {
    const unsigned int threads = ResampleThreads(u) > 2 ? ResampleThreads(u) - 2 : 1;
    bmr::ParallelFor("resample meshes", static_cast<int>(u.resamples), threads, [&](int k, int) {
      if (m_Stop)
      {
        return;
      }
      try
      {
        std::vector<PipelineStage> untimed;
        StageClock                 quiet(nullptr, untimed);
        m_Meshes[k] = MeshLabelImage(
          movingLabels, ResampleMeshScene(scene, u, static_cast<unsigned int>(k)), quiet, "resample mesh");
      }
      catch (const std::exception &)
      {
        // Left empty: the resample meshes again and reports the failure where it belongs.
      }
    });
  })
{}

ResampleMeshPrefetch::~ResampleMeshPrefetch()
{
  m_Stop = true; // the mesh under way is finished and waited for by m_Task
}

std::vector<bmr::TetrahedralMesh>
ResampleMeshPrefetch::Finish()
{
  m_Stop = true;
  m_Task.Wait(); // the meshes not started stay empty: their resamples mesh them
  return std::move(m_Meshes);
}

} // namespace pipeline
} // namespace itk
