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

// CGAL lives in the units of the CGAL mesher only (this one, the mesh generation and extraction, and
// bmrCgalMeshCriteria.cxx): they are by far the most expensive files of the module to compile, and keeping
// CGAL here keeps it (and its Boost/GMP dependencies) out of every public header.

#include "bmrMesher.h"
#include "bmrError.h"

// Sequential meshing only: the parallel Mesh_3 is not reproducible run to run.
#ifdef CGAL_CONCURRENT_MESH_3
#  error "bmrCgalMesher.cxx must be compiled without CGAL_CONCURRENT_MESH_3 (meshes must be reproducible)"
#endif

#include "bmrCgalMesher.h"

#include <CGAL/Handle_hash_function.h>
#include <CGAL/Image_3.h>
#include <CGAL/ImageIO.h>
#include <CGAL/Random.h>
#include <CGAL/refine_mesh_3.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <iterator>
#include <limits>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <tuple>
#include <unordered_map>
#include <utility>
#include <vector>

namespace bmr {
namespace {

using meshing::CheckParameters;
using meshing::Complex;
using meshing::Criteria;
using meshing::Kernel;
using meshing::LatticeIndex;
using meshing::MakeCriteria;
using meshing::MeshDomain;
using meshing::Point;
using meshing::SampleLattice;
using meshing::Triangulation;
using meshing::Vertex_handle;

const std::array<LatticeIndex, 6> AxisSteps = {
  { { { -1, 0, 0 } }, { { 1, 0, 0 } }, { { 0, -1, 0 } }, { { 0, 1, 0 } }, { { 0, 0, -1 } }, { { 0, 0, 1 } } }
};

LatticeIndex
operator+(const LatticeIndex & a, const LatticeIndex & b)
{
  return { { a[0] + b[0], a[1] + b[1], a[2] + b[2] } };
}

/** The seeds of InsertComponentSeeds(): one sample of every 6-connected component of every non-zero label of
 * \a lattice, in buffer order. */
std::vector<std::size_t>
ComponentSeeds(const SampleLattice & lattice)
{
  const std::size_t    count = lattice.NumberOfSamples();
  const std::int32_t * labels = lattice.labels;

  std::vector<bool>        visited(count, false);
  std::vector<std::size_t> stack;
  std::vector<std::size_t> seeds;
  for (std::size_t start = 0; start < count; ++start)
  {
    if (visited[start] || labels[start] == 0)
    {
      continue;
    }
    // The first sample of a component in buffer order is its seed: a cheap,
    // deterministic choice that is guaranteed to lie on the component surface.
    seeds.push_back(start);
    visited[start] = true;
    stack.assign(1, start);
    while (!stack.empty())
    {
      const LatticeIndex index = lattice.IndexOf(stack.back());
      stack.pop_back();
      for (const LatticeIndex & step : AxisSteps)
      {
        const LatticeIndex neighbor = index + step;
        if (!lattice.Contains(neighbor))
        {
          continue;
        }
        const std::size_t offset = lattice.OffsetOf(neighbor);
        if (!visited[offset] && labels[offset] == labels[start])
        {
          visited[offset] = true;
          stack.push_back(offset);
        }
      }
    }
  }
  return seeds;
}

/** Inserts surface points found by shooting, from one sample of every
 * 6-connected component of every non-zero label, along the six axis directions
 * to the first sample with another label.
 *
 * CGAL's default initialization shoots random rays from the center of the
 * bounding box and keeps the first 12 hits; Delaunay refinement only discovers
 * surfaces that the initial triangulation comes close to, so small or
 * off-center structures (a kidney, a lesion) could be silently missing from
 * the mesh. Seeding each component makes every label present in the input
 * present in the mesh, deterministically. Returns the number of points. */
std::size_t
InsertComponentSeeds(Complex & c3t3, const MeshDomain & domain, const SampleLattice & lattice, double minimumDistance)
{
  const std::int32_t *           labels = lattice.labels;
  const std::vector<std::size_t> seeds = ComponentSeeds(lattice);

  Triangulation &                          tr = c3t3.triangulation();
  const auto                               weighted = tr.geom_traits().construct_weighted_point_3_object();
  const MeshDomain::Construct_intersection intersect = domain.construct_intersection_object();
  std::size_t                              inserted = 0;
  // Rays from a sample next to the surface hit it at nearly the same point; vertices closer than a
  // fraction of the facet size would survive refinement as a cluster of flat elements.
  std::vector<Kernel::Point_3> placed;
  for (const std::size_t seed : seeds)
  {
    const LatticeIndex origin = lattice.IndexOf(seed);
    for (const LatticeIndex & step : AxisSteps)
    {
      LatticeIndex target = origin + step;
      while (lattice.Contains(target) && labels[lattice.OffsetOf(target)] == labels[seed])
      {
        target = target + step;
      }
      const MeshDomain::Intersection hit =
        intersect(Kernel::Segment_3(lattice.PointAt(origin), lattice.PointAt(target)));
      if (std::get<2>(hit) == 0)
      {
        continue; // the domain function disagrees with the lattice here
      }
      const Kernel::Point_3 point = std::get<0>(hit);
      bool                  tooClose = false;
      for (const auto & q : placed)
      {
        tooClose = tooClose || CGAL::squared_distance(point, q) < minimumDistance * minimumDistance;
      }
      if (tooClose)
      {
        continue;
      }
      placed.push_back(point);
      const Vertex_handle vertex = tr.insert(weighted(point));
      if (vertex != Vertex_handle())
      {
        // Same bookkeeping as CGAL's own initialization: a surface point.
        c3t3.set_dimension(vertex, 2);
        c3t3.set_index(vertex, std::get<1>(hit));
        ++inserted;
      }
    }
  }
  return inserted;
}

/** Seeds, refines and optionally optimizes. The perturber and exuder get an
 * explicit time limit of 0 (= none): without it, refine_mesh_3 uses the wall
 * time of the refinement as their budget, which makes the result depend on
 * machine load. */
Complex
GenerateMesh(const MeshDomain &        domain,
             const SampleLattice &     lattice,
             const MeshingParameters & parameters,
             const char *              where)
{
  namespace p = CGAL::parameters;
  const Criteria criteria = MakeCriteria(parameters, lattice);

  Complex c3t3;
  InsertComponentSeeds(c3t3, domain, lattice, 0.5 * std::min(parameters.facetSize, parameters.cellSize));
  // No fallback to CGAL's random shooting here: it loops forever when the
  // domain function is 0 everywhere, which is what CGAL sees of labels that lie
  // only in the last slice of an image (its interpolation stops there).
  if (c3t3.triangulation().dimension() != 3)
  {
    Fail(where,
         "could not find enough points on the labeled surfaces to start the mesh refinement (labeled regions "
         "too thin, or only in the last slice of the volume)");
  }

  // Perturbation lifts the minimum dihedral angle from near zero to the sliver bound, cheaply at small bounds;
  // exudation costs several times more and adds little, so it is opt-in (docs/history/benchmarks.md, mesh quality).
  if (parameters.optimize && parameters.exude)
  {
    CGAL::refine_mesh_3(c3t3,
                        domain,
                        criteria,
                        p::perturb(p::time_limit = 0, p::sliver_bound = parameters.sliverBound),
                        p::exude(p::time_limit = 0),
                        p::no_lloyd(),
                        p::no_odt(),
                        p::no_reset_c3t3());
  }
  else if (parameters.optimize)
  {
    CGAL::refine_mesh_3(c3t3,
                        domain,
                        criteria,
                        p::perturb(p::time_limit = 0, p::sliver_bound = parameters.sliverBound),
                        p::no_exude(),
                        p::no_lloyd(),
                        p::no_odt(),
                        p::no_reset_c3t3());
  }
  else
  {
    CGAL::refine_mesh_3(
      c3t3, domain, criteria, p::no_perturb(), p::no_exude(), p::no_lloyd(), p::no_odt(), p::no_reset_c3t3());
  }
  return c3t3;
}

/** Copies the cells of the complex into a TetrahedralMesh. Nodes are numbered
 * in order of first appearance, so the numbering depends only on the
 * (deterministic) cell order of the triangulation. Orientation is fixed after
 * the mapping to physical space because a direction matrix with negative
 * determinant mirrors every element. */
template<typename TMapToPhysical>
TetrahedralMesh
ExtractMesh(const Complex & c3t3, const TMapToPhysical & toPhysical, const char * where)
{
  TetrahedralMesh mesh;
  const auto      numberOfCells = static_cast<std::size_t>(c3t3.number_of_cells_in_complex());
  if (numberOfCells == 0)
  {
    Fail(where, "CGAL produced no tetrahedron; the meshing sizes may be too large for the labeled regions");
  }
  if (numberOfCells > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max() / 4))
  {
    Fail(where, "CGAL produced more tetrahedra than 32-bit node indices can address");
  }
  mesh.tetrahedra.reserve(4 * numberOfCells);
  mesh.labels.reserve(numberOfCells);

  std::unordered_map<Vertex_handle, std::int32_t, CGAL::Handle_hash_function> nodeOfVertex;
  nodeOfVertex.reserve(numberOfCells / 4);
  for (auto cell = c3t3.cells_in_complex_begin(); cell != c3t3.cells_in_complex_end(); ++cell)
  {
    std::array<std::int32_t, 4> nodes;
    for (int v = 0; v < 4; ++v)
    {
      const Vertex_handle vertex = cell->vertex(v);
      const auto          found = nodeOfVertex.emplace(vertex, static_cast<std::int32_t>(nodeOfVertex.size()));
      if (found.second)
      {
        const std::array<double, 3> x = toPhysical(vertex->point().point());
        mesh.points.insert(mesh.points.end(), x.begin(), x.end());
      }
      nodes[v] = found.first->second;
    }
    const double * x0 = &mesh.points[3 * static_cast<std::size_t>(nodes[0])];
    const double * x1 = &mesh.points[3 * static_cast<std::size_t>(nodes[1])];
    const double * x2 = &mesh.points[3 * static_cast<std::size_t>(nodes[2])];
    const double * x3 = &mesh.points[3 * static_cast<std::size_t>(nodes[3])];
    const double   a[3] = { x1[0] - x0[0], x1[1] - x0[1], x1[2] - x0[2] };
    const double   b[3] = { x2[0] - x0[0], x2[1] - x0[1], x2[2] - x0[2] };
    const double   c[3] = { x3[0] - x0[0], x3[1] - x0[1], x3[2] - x0[2] };
    const double   volume =
      a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
    if (volume < 0.0)
    {
      std::swap(nodes[2], nodes[3]);
    }
    mesh.tetrahedra.insert(mesh.tetrahedra.end(), nodes.begin(), nodes.end());
    mesh.labels.push_back(static_cast<std::int32_t>(c3t3.subdomain_index(cell)));
  }
  return mesh;
}

/** Meshes the labeled domain of \a labelAt (0 outside the ball (\a center, \a boundingRadius), which must hold it)
 * with CGAL's exact function domain, seeded from \a lattice; \a toPhysical maps the result. */
template<typename TLabelAt, typename TToPhysical>
TetrahedralMesh
MeshLabelFunction(const TLabelAt &              labelAt,
                  const std::array<double, 3> & center,
                  double                        boundingRadius,
                  const SampleLattice &         lattice,
                  const MeshingParameters &     parameters,
                  const TToPhysical &           toPhysical,
                  const char *                  where)
{
  // Exact function: the bisection only needs to be well below facetDistance.
  const double relativeErrorBound = 2.0 * 0.01 * parameters.facetDistance / (2.0 * std::sqrt(3.0) * boundingRadius);

  CGAL::get_default_random() = CGAL::Random(parameters.randomSeed);
  CGAL::Random domainRandom(parameters.randomSeed); // must outlive the domain
  namespace p = CGAL::parameters;
  // Not create_implicit_mesh_domain(): that one wraps a signed function into a
  // single subdomain (f < 0 -> 1) and would lose the labels.
  const MeshDomain domain(std::function<int(const Point &)>([&labelAt](const Point & point) {
                            return static_cast<int>(labelAt(point.x(), point.y(), point.z()));
                          }),
                          Kernel::Sphere_3(Point(center[0], center[1], center[2]), boundingRadius * boundingRadius),
                          p::relative_error_bound = relativeErrorBound,
                          p::p_rng = &domainRandom);
  const Complex    c3t3 = GenerateMesh(domain, lattice, parameters, where);
  return ExtractMesh(c3t3, toPhysical, where);
}

/** The map from Mesh_3's space for a grid, the scaled index space q = diag(spacing) index (exact, origin 0; CGAL's
 * images have neither direction cosines nor a double-precision origin), to physical mm. */
auto
ScaledIndexToPhysical(const GridGeometry & grid)
{
  return [&grid](const Point & point) {
    const double          q[3] = { point.x(), point.y(), point.z() };
    std::array<double, 3> x;
    for (unsigned r = 0; r < 3; ++r)
    {
      x[r] = grid.origin[r] + grid.direction[3 * r] * q[0] + grid.direction[3 * r + 1] * q[1] +
             grid.direction[3 * r + 2] * q[2];
    }
    return x;
  };
}

} // namespace


TetrahedralMesh
MeshLabelVolume(const std::int32_t * labels, const GridGeometry & grid, const MeshingParameters & parameters)
{
  const char * where = "bmr::MeshLabelVolume";
  grid.Validate("label volume");
  CheckParameters(where, parameters);
  const std::size_t numberOfVoxels = grid.GetNumberOfVoxels();
  if (labels == nullptr || numberOfVoxels == 0)
  {
    Fail(where, "the label volume is empty");
  }
  if (grid.size[0] < 2 || grid.size[1] < 2 || grid.size[2] < 2)
  {
    Fail(where, "the label volume must have at least 2 voxels along each axis (CGAL interpolates between voxels)");
  }
  if (std::none_of(labels, labels + numberOfVoxels, [](std::int32_t label) { return label != 0; }))
  {
    Fail(where, "the label volume contains no non-zero label");
  }

  // CGAL::Image_3 has neither direction cosines nor a double-precision origin,
  // so the mesh is generated in the scaled index space diag(spacing) * index
  // (exact, origin 0) and mapped to physical space afterwards.
  _image * raw = ::_createImage(grid.size[0],
                                grid.size[1],
                                grid.size[2],
                                1,
                                grid.spacing[0],
                                grid.spacing[1],
                                grid.spacing[2],
                                sizeof(std::int32_t),
                                WK_FIXED,
                                SGN_SIGNED);
  if (raw == nullptr || raw->data == nullptr)
  {
    if (raw != nullptr)
    {
      ::_freeImage(raw);
    }
    Fail(where, "could not allocate the CGAL image");
  }
  std::memcpy(raw->data, labels, numberOfVoxels * sizeof(std::int32_t));
  const CGAL::Image_3 image(raw); // takes ownership of raw

  // The bisection tolerance is relative to the bounding box diagonal; a tenth
  // of the finest voxel size (or of the surface tolerance) is all a voxelized
  // surface can justify, and a fixed 1e-3 would be 0.3 mm on a body-sized image.
  const double minimumSpacing = std::min({ grid.spacing[0], grid.spacing[1], grid.spacing[2] });
  const double tolerance = 0.1 * std::min(minimumSpacing, parameters.facetDistance);
  double       diagonal2 = 0.0;
  for (unsigned d = 0; d < 3; ++d)
  {
    // CGAL's bounding box of an image: one unit beyond each side.
    const double extent = static_cast<double>(grid.size[d]) * grid.spacing[d] + 2.0;
    diagonal2 += extent * extent;
  }
  const double relativeErrorBound = 2.0 * tolerance / std::sqrt(diagonal2);

  CGAL::get_default_random() = CGAL::Random(parameters.randomSeed);
  CGAL::Random domainRandom(parameters.randomSeed); // must outlive the domain
  namespace p = CGAL::parameters;
  const MeshDomain domain = MeshDomain::create_labeled_image_mesh_domain(
    image, p::relative_error_bound = relativeErrorBound, p::value_outside = 0, p::p_rng = &domainRandom);

  SampleLattice lattice;
  for (unsigned d = 0; d < 3; ++d)
  {
    lattice.size[d] = static_cast<std::ptrdiff_t>(grid.size[d]);
  }
  lattice.step = grid.spacing;
  lattice.labels = labels;
  const Complex c3t3 = GenerateMesh(domain, lattice, parameters, where);

  const auto toPhysical = ScaledIndexToPhysical(grid);
  return ExtractMesh(c3t3, toPhysical, where);
}


TetrahedralMesh
MeshImplicitLabels(const std::function<std::int32_t(double, double, double)> & labelAt,
                   const std::array<double, 3> &                               center,
                   double                                                      boundingRadius,
                   const MeshingParameters &                                   parameters)
{
  const char * where = "bmr::MeshImplicitLabels";
  CheckParameters(where, parameters);
  if (!labelAt)
  {
    Fail(where, "no labeling function given");
  }
  if (!std::isfinite(boundingRadius) || !(boundingRadius > 0.0))
  {
    Fail(where, "boundingRadius must be positive and finite, got " + std::to_string(boundingRadius));
  }
  if (!std::isfinite(center[0]) || !std::isfinite(center[1]) || !std::isfinite(center[2]))
  {
    Fail(where, "the center of the bounding ball must be finite");
  }

  // Labelled_mesh_domain_3 requires the domain to lie inside the bounding
  // sphere; clipping the function to the ball makes that true for any labelAt.
  const double radius2 = boundingRadius * boundingRadius;
  const auto   clippedLabel = [&labelAt, center, radius2](double x, double y, double z) -> std::int32_t {
    const double dx = x - center[0];
    const double dy = y - center[1];
    const double dz = z - center[2];
    return dx * dx + dy * dy + dz * dz > radius2 ? 0 : labelAt(x, y, z);
  };

  // A coarse sampling of the ball both proves the domain non-empty (CGAL's own
  // initialization would otherwise search forever) and provides the seeds.
  constexpr std::ptrdiff_t samplesPerAxis = 33;
  SampleLattice            lattice;
  lattice.size = { { samplesPerAxis, samplesPerAxis, samplesPerAxis } };
  const double step = 2.0 * boundingRadius / static_cast<double>(samplesPerAxis - 1);
  for (unsigned d = 0; d < 3; ++d)
  {
    lattice.first[d] = center[d] - boundingRadius;
    lattice.step[d] = step;
  }
  lattice.ownedLabels.resize(lattice.NumberOfSamples());
  bool anyLabel = false;
  for (std::size_t offset = 0; offset < lattice.ownedLabels.size(); ++offset)
  {
    const Point sample = lattice.PointAt(lattice.IndexOf(offset));
    lattice.ownedLabels[offset] = clippedLabel(sample.x(), sample.y(), sample.z());
    anyLabel = anyLabel || lattice.ownedLabels[offset] != 0;
  }
  if (!anyLabel)
  {
    Fail(where,
         "the labeling function is 0 at every sample of the bounding ball: the domain is empty or thinner than " +
           std::to_string(step) + " mm");
  }
  lattice.labels = lattice.ownedLabels.data();

  const auto toPhysical = [](const Point & point) {
    return std::array<double, 3>{ { point.x(), point.y(), point.z() } };
  };
  return MeshLabelFunction(clippedLabel, center, boundingRadius, lattice, parameters, toPhysical, where);
}

TetrahedralMesh
MeshImplicitLabelsOnGrid(const std::function<std::int32_t(double, double, double)> & labelAt,
                         const GridGeometry &                                        grid,
                         const std::vector<std::int32_t> &                           gridLabels,
                         const MeshingParameters &                                   parameters)
{
  const char * where = "bmr::MeshImplicitLabelsOnGrid";
  grid.Validate("label grid");
  CheckParameters(where, parameters);
  if (!labelAt)
  {
    Fail(where, "no labeling function given");
  }
  if (gridLabels.size() != grid.GetNumberOfVoxels() || grid.size[0] < 2 || grid.size[1] < 2 || grid.size[2] < 2)
  {
    Fail(where, "the grid's labels must hold one value per voxel of a grid with at least 2 voxels along each axis");
  }
  // As MeshLabelVolume(): meshed in the scaled index space q = diag(spacing) index, whose box [0, (n - 1) h] is the
  // voxel centres', and mapped to physical space afterwards.
  const auto            toPhysical = ScaledIndexToPhysical(grid);
  std::array<double, 3> extent, center;
  double                radius2 = 0.0;
  for (unsigned d = 0; d < 3; ++d)
  {
    extent[d] = static_cast<double>(grid.size[d] - 1) * grid.spacing[d];
    center[d] = 0.5 * extent[d];
    radius2 += center[d] * center[d];
  }
  const auto clippedLabel = [&labelAt, &toPhysical, extent](double x, double y, double z) -> std::int32_t {
    if (x < 0.0 || y < 0.0 || z < 0.0 || x > extent[0] || y > extent[1] || z > extent[2])
    {
      return 0;
    }
    const std::array<double, 3> p = toPhysical(Point(x, y, z));
    return labelAt(p[0], p[1], p[2]);
  };
  SampleLattice lattice;
  for (unsigned d = 0; d < 3; ++d)
  {
    lattice.size[d] = static_cast<std::ptrdiff_t>(grid.size[d]);
  }
  lattice.step = grid.spacing;
  lattice.labels = gridLabels.data();
  // The ball holds the box, with room for the bisection's end points.
  const double boundingRadius = std::sqrt(radius2) + std::max({ grid.spacing[0], grid.spacing[1], grid.spacing[2] });
  return MeshLabelFunction(clippedLabel, center, boundingRadius, lattice, parameters, toPhysical, where);
}

} // namespace bmr
