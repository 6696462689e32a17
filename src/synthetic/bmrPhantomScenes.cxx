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
#include "bmrPhantom.h"

#include <ostream>

namespace bmr {

Scene
PelvisPhantomScene(double prostateE, bool unknown, double prostateNu)
{
  Scene s;
  s.name = "pelvis phantom";
  using R = LabelRoleEnum;
  SceneLabel prostate{ "prostate", PelvisProstate, unknown ? R::UnknownMaterial : R::Material, prostateE, prostateNu };
  if (unknown)
  {
    prostate.lowerBound = 20.0;
    prostate.upperBound = 600.0;
  }
  s.labels = { { "air", PelvisAir, R::Outside },
               { "soft_tissue", PelvisSoftTissue, R::Material, 10.0, 0.35 },
               prostate,
               { "bladder", PelvisBladder, R::Hollow },
               { "rectum", PelvisRectum, R::Hollow },
               { "bone", PelvisBone, R::Fixed } };
  s.gauge = "soft_tissue";
  s.forceSurfaces = { "bladder", "rectum" };
  s.objective = { { "prostate", 1.0 }, { "bladder", 1.0 }, { "rectum", 1.0 } };
  s.roiMargin = 25.0;
  // The estimation's sizes are 0.75 x the truth's base sizes, its surface criteria a further 0.85 x: the surfaces
  // carry most of the discretization error, and the finer surfaces brought the recovered modulus close to the
  // converged mean of much finer uniform meshes (docs/history/benchmarks.md, mesh convergence). The truth refines
  // its own base sizes (PhantomSettings::truthRefinement).
  const double scale = unknown ? 0.75 : 1.0;
  const double surfaces = unknown ? 0.85 : 1.0;
  s.mesh.cellSize = 7.0 * scale;
  s.mesh.facetSize = 6.0 * scale * surfaces;
  s.mesh.facetDistance = 0.5 * scale * surfaces;
  s.mesh.cellSizePerLabel[PelvisProstate] = 4.5 * scale;
  return s;
}

Scene
SpherePhantomScene(double innerE, bool unknown)
{
  Scene s;
  s.name = "concentric spheres";
  using R = LabelRoleEnum;
  SceneLabel inner{ "inner", SphereInnerCore, unknown ? R::UnknownMaterial : R::Material, innerE, 0.40 };
  if (unknown)
  {
    inner.lowerBound = 30.0;
    inner.upperBound = 300.0;
  }
  s.labels = { { "outside", SphereOutside, R::Outside },
               { "outer", SphereOuterShell, R::Material, 10.0, 0.35 },
               inner };
  s.gauge = "outer";
  s.forceSurfaces = { "outside" };
  s.objective = { { "inner", 1.0 }, { "outer", 1.0 } };
  s.mesh.cellSize = 4.0;
  s.mesh.facetSize = 3.0;
  s.mesh.facetDistance = 0.5;
  return s;
}

std::ostream &
operator<<(std::ostream & os, WallFillingEnum value)
{
  return os << (value == WallFillingEnum::AlongNormals ? "bmr::WallFillingEnum::AlongNormals"
                                                       : "bmr::WallFillingEnum::FromPoint");
}

} // namespace bmr
