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

// All of CGAL lives in this translation unit: it is by far the most expensive
// file of the module to compile, and keeping it here keeps CGAL (and its
// Boost/GMP dependencies) out of every public header.

#include "bmrMesher.h"
#include "bmrError.h"

// Sequential meshing only: the parallel Mesh_3 is not reproducible run to run.
#ifdef CGAL_CONCURRENT_MESH_3
#  error "bmrCgalMesher.cxx must be compiled without CGAL_CONCURRENT_MESH_3 (meshes must be reproducible)"
#endif

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Handle_hash_function.h>
#include <CGAL/Image_3.h>
#include <CGAL/ImageIO.h>
#include <CGAL/Labeled_mesh_domain_3.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_constant_domain_field_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
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

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using MeshDomain = CGAL::Labeled_mesh_domain_3<Kernel>;
using Triangulation = CGAL::Mesh_triangulation_3<MeshDomain, CGAL::Default, CGAL::Sequential_tag>::type;
using Complex = CGAL::Mesh_complex_3_in_triangulation_3<Triangulation>;
using Criteria = CGAL::Mesh_criteria_3<Triangulation>;
using LabelSizingField = CGAL::Mesh_constant_domain_field_3<MeshDomain::R, MeshDomain::Index>;
using Vertex_handle = Triangulation::Vertex_handle;

using LatticeIndex = std::array<std::ptrdiff_t, 3>;

/** A regular lattice of labels from which the initial surface points are
 * shot. For a label volume this is the image itself; for an implicit domain
 * it is a coarse sampling of the bounding ball. Index 0 runs fastest. */
struct SampleLattice
{
  LatticeIndex              size{ { 0, 0, 0 } };
  std::array<double, 3>     first{ { 0, 0, 0 } };
  std::array<double, 3>     step{ { 1, 1, 1 } };
  const std::int32_t *      labels{ nullptr };
  std::vector<std::int32_t> ownedLabels;

  std::size_t
  NumberOfSamples() const
  {
    return static_cast<std::size_t>(size[0] * size[1] * size[2]);
  }

  bool
  Contains(const LatticeIndex & index) const
  {
    return index[0] >= 0 && index[0] < size[0] && index[1] >= 0 && index[1] < size[1] && index[2] >= 0 &&
           index[2] < size[2];
  }

  std::size_t
  OffsetOf(const LatticeIndex & index) const
  {
    return static_cast<std::size_t>(index[0] + size[0] * (index[1] + size[1] * index[2]));
  }

  LatticeIndex
  IndexOf(std::size_t offset) const
  {
    const auto o = static_cast<std::ptrdiff_t>(offset);
    return { { o % size[0], (o / size[0]) % size[1], o / (size[0] * size[1]) } };
  }

  /** Indices one step outside the lattice are allowed: they are outside the
   * domain by construction. */
  Point
  PointAt(const LatticeIndex & index) const
  {
    return Point(first[0] + step[0] * static_cast<double>(index[0]),
                 first[1] + step[1] * static_cast<double>(index[1]),
                 first[2] + step[2] * static_cast<double>(index[2]));
  }
};

const std::array<LatticeIndex, 6> AxisSteps = {
  { { { -1, 0, 0 } }, { { 1, 0, 0 } }, { { 0, -1, 0 } }, { { 0, 1, 0 } }, { { 0, 0, -1 } }, { { 0, 0, 1 } } }
};

LatticeIndex
operator+(const LatticeIndex & a, const LatticeIndex & b)
{
  return { { a[0] + b[0], a[1] + b[1], a[2] + b[2] } };
}

void
CheckPositiveFinite(const char * where, const char * name, double value)
{
  if (!std::isfinite(value) || !(value > 0.0))
  {
    std::ostringstream message;
    message << "MeshingParameters::" << name << " must be positive and finite, got " << value;
    Fail(where, message.str());
  }
}

void
CheckParameters(const char * where, const MeshingParameters & parameters)
{
  CheckPositiveFinite(where, "cellSize", parameters.cellSize);
  CheckPositiveFinite(where, "facetSize", parameters.facetSize);
  CheckPositiveFinite(where, "facetDistance", parameters.facetDistance);
  CheckPositiveFinite(where, "facetAngle", parameters.facetAngle);
  CheckPositiveFinite(where, "cellRadiusEdgeRatio", parameters.cellRadiusEdgeRatio);
  // Beyond these bounds Delaunay refinement is not guaranteed to terminate
  // (CGAL Mesh_3 manual), so a typo would hang instead of failing.
  if (parameters.facetAngle > 30.0)
  {
    Fail(where,
         "MeshingParameters::facetAngle must not exceed 30 degrees (refinement may not terminate), got " +
           std::to_string(parameters.facetAngle));
  }
  if (parameters.cellRadiusEdgeRatio < 2.0)
  {
    Fail(where,
         "MeshingParameters::cellRadiusEdgeRatio must be at least 2 (refinement may not terminate), got " +
           std::to_string(parameters.cellRadiusEdgeRatio));
  }
  if (!(parameters.refineSize >= 0.0 && std::isfinite(parameters.refineSize)) ||
      !(parameters.refineDistance >= 0.0 && std::isfinite(parameters.refineDistance)))
  {
    Fail(where, "MeshingParameters::refineSize and refineDistance must be finite and >= 0");
  }
  for (const auto & keyAndSizes : parameters.SizesPerLabel())
  {
    for (const auto & labelAndSize : *keyAndSizes.second)
    {
      if (!std::isfinite(labelAndSize.second) || !(labelAndSize.second > 0.0))
      {
        std::ostringstream message;
        message << "MeshingParameters: " << keyAndSizes.first << '[' << labelAndSize.first
                << "] must be positive and finite, got " << labelAndSize.second;
        Fail(where, message.str());
      }
    }
  }
  if (parameters.optimize && !(parameters.sliverBound > 0.0 && parameters.sliverBound < 60.0))
  {
    Fail(where,
         "MeshingParameters::sliverBound must lie in (0, 60) degrees (optimize = false skips the perturbation), got " +
           std::to_string(parameters.sliverBound));
  }
}

/** One pass of the exact distance transform along a line (Felzenszwalb and Huttenlocher 2012): out[q] =
 * min_r (h (q - r))^2 + f[r], the lower envelope of the parabolas rooted at the finite f[r]; infinite when none. */
void
LowerEnvelope(const std::vector<double> & f, double h, std::vector<double> & out)
{
  constexpr double            infinity = std::numeric_limits<double>::infinity();
  std::vector<std::ptrdiff_t> roots;
  std::vector<double>         from; // where each root's parabola starts to be the lowest
  for (std::ptrdiff_t q = 0; q < static_cast<std::ptrdiff_t>(f.size()); ++q)
  {
    if (!std::isfinite(f[q]))
    {
      continue;
    }
    const double x = h * double(q);
    double       start = -infinity;
    while (!roots.empty())
    {
      const double y = h * double(roots.back());
      start = ((f[q] + x * x) - (f[roots.back()] + y * y)) / (2.0 * (x - y));
      if (start > from.back())
      {
        break;
      }
      roots.pop_back();
      from.pop_back();
      start = -infinity;
    }
    roots.push_back(q);
    from.push_back(start);
  }
  std::size_t k = 0;
  for (std::size_t q = 0; q < f.size(); ++q)
  {
    const double x = h * double(q);
    while (k + 1 < roots.size() && from[k + 1] < x)
    {
      ++k;
    }
    const double dx = roots.empty() ? 0.0 : x - h * double(roots[k]);
    out[q] = roots.empty() ? infinity : dx * dx + f[roots[k]];
  }
}

/** Whether each lattice sample lies within \a distance [mm] of a sample labeled with one of \a labels: the exact
 * Euclidean distance transform, one LowerEnvelope() pass per axis with that axis' step. */
std::vector<char>
WithinDistanceOfLabels(const SampleLattice & lattice, const std::vector<std::int32_t> & labels, double distance)
{
  const std::size_t   n = lattice.NumberOfSamples();
  std::vector<double> d2(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    const bool in = std::find(labels.begin(), labels.end(), lattice.labels[i]) != labels.end();
    d2[i] = in ? 0.0 : std::numeric_limits<double>::infinity();
  }
  const std::size_t strides[3] = { 1,
                                   static_cast<std::size_t>(lattice.size[0]),
                                   static_cast<std::size_t>(lattice.size[0] * lattice.size[1]) };
  for (int axis = 0; axis < 3; ++axis)
  {
    const std::size_t   length = static_cast<std::size_t>(lattice.size[axis]);
    std::vector<double> line(length), out(length);
    for (std::size_t start = 0; start < n; ++start)
    {
      if ((start / strides[axis]) % length != 0)
      {
        continue; // not the first sample of a line along this axis
      }
      for (std::size_t q = 0; q < length; ++q)
      {
        line[q] = d2[start + q * strides[axis]];
      }
      LowerEnvelope(line, lattice.step[axis], out);
      for (std::size_t q = 0; q < length; ++q)
      {
        d2[start + q * strides[axis]] = out[q];
      }
    }
  }
  std::vector<char> within(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    within[i] = d2[i] <= distance * distance;
  }
  return within;
}

/** A Mesh_3 size field: \a base's size, at most \a refined where the lattice sample nearest to the point is marked
 * in \a near (null: none). Mesh_3 asks it at cell circumcentres and facet surface centres. */
template<typename TBase>
struct RefinedSizeField
{
  TBase                                    base;
  std::shared_ptr<const std::vector<char>> near;
  const SampleLattice *                    lattice{ nullptr };
  double                                   refined{ 0.0 };

  double
  operator()(const Point & p, const int dimension, const MeshDomain::Index & index) const
  {
    const double size = base(p, dimension, index);
    if (!near)
    {
      return size;
    }
    LatticeIndex i;
    const double x[3] = { p.x(), p.y(), p.z() };
    for (int a = 0; a < 3; ++a)
    {
      const double q = std::round((x[a] - lattice->first[a]) / lattice->step[a]);
      i[a] = static_cast<std::ptrdiff_t>(std::clamp(q, 0.0, double(lattice->size[a] - 1)));
    }
    return (*near)[lattice->OffsetOf(i)] ? std::min(size, refined) : size;
  }
};

struct UniformSize
{
  double size;
  double
  operator()(const Point &, const int, const MeshDomain::Index &) const
  {
    return size;
  }
};

/** A facet criterion's bound as a domain field keyed by surface patch (Mesh_3 evaluates facet criteria with the
 * facet's patch, the pair of labels it separates): \a global, and on a patch between labels a and b at most the
 * per-label bound of a and of b. \a present: the labels of the lattice. */
LabelSizingField
PatchBoundField(double global, const std::map<std::int32_t, double> & perLabel, const std::set<std::int32_t> & present)
{
  LabelSizingField field(global);
  for (const auto & labelAndBound : perLabel)
  {
    for (const std::int32_t other : present)
    {
      if (other == labelAndBound.first)
      {
        continue;
      }
      const auto   found = perLabel.find(other);
      const double bound = std::min({ global, labelAndBound.second, found == perLabel.end() ? global : found->second });
      // The domain orders a patch's labels (Labeled_mesh_domain_3::make_surface_index).
      const MeshDomain::Surface_patch_index patch(std::min(other, labelAndBound.first),
                                                  std::max(other, labelAndBound.first));
      field.set_size(bound, 2, MeshDomain::Index(patch));
    }
  }
  return field;
}

/** The labels of \a lattice, and 0: the outside of the domain. */
std::set<std::int32_t>
LatticeLabels(const SampleLattice & lattice)
{
  std::set<std::int32_t> present{ 0 };
  std::int32_t           last = 0;
  for (std::size_t i = 0; i < lattice.NumberOfSamples(); ++i)
  {
    if (lattice.labels[i] != last) // runs of one label are the rule
    {
      last = lattice.labels[i];
      present.insert(last);
    }
  }
  return present;
}

/** The per-label cell size goes through a domain field keyed by subdomain
 * index, because Mesh_3 evaluates the cell size criterion with the subdomain
 * index of the cell being refined, the per-label facet bounds through fields keyed by surface patch
 * (PatchBoundField); the local refinement (MeshingParameters::refineNearLabels) caps both the cell
 * and the facet size near the given labels, found on \a lattice. */
Criteria
MakeCriteria(const MeshingParameters & parameters, const SampleLattice & lattice)
{
  namespace p = CGAL::parameters;
  LabelSizingField cellSize(parameters.cellSize);
  for (const auto & labelAndSize : parameters.cellSizePerLabel)
  {
    cellSize.set_size(labelAndSize.second, 3, MeshDomain::Index(static_cast<int>(labelAndSize.first)));
  }
  const auto near = parameters.Refines() ? std::make_shared<const std::vector<char>>(WithinDistanceOfLabels(
                                             lattice, parameters.refineNearLabels, parameters.refineDistance))
                                         : nullptr;
  if (parameters.HasFacetBoundsPerLabel())
  {
    const std::set<std::int32_t> present = LatticeLabels(lattice);
    const LabelSizingField facetSize = PatchBoundField(parameters.facetSize, parameters.facetSizePerLabel, present);
    return Criteria(
      p::facet_angle = parameters.facetAngle,
      p::facet_size = RefinedSizeField<LabelSizingField>{ facetSize, near, &lattice, parameters.refineSize },
      p::facet_distance = PatchBoundField(parameters.facetDistance, parameters.facetDistancePerLabel, present),
      p::cell_radius_edge_ratio = parameters.cellRadiusEdgeRatio,
      p::cell_size = RefinedSizeField<LabelSizingField>{ cellSize, near, &lattice, parameters.refineSize });
  }
  if (parameters.Refines())
  {
    return Criteria(
      p::facet_angle = parameters.facetAngle,
      p::facet_size =
        RefinedSizeField<UniformSize>{ UniformSize{ parameters.facetSize }, near, &lattice, parameters.refineSize },
      p::facet_distance = parameters.facetDistance,
      p::cell_radius_edge_ratio = parameters.cellRadiusEdgeRatio,
      p::cell_size = RefinedSizeField<LabelSizingField>{ cellSize, near, &lattice, parameters.refineSize });
  }
  // Without refinement the criteria as they always were (a scalar size where there is no per-label one), so that
  // every mesh made before the refinement existed is made again node for node.
  if (parameters.cellSizePerLabel.empty())
  {
    return Criteria(p::facet_angle = parameters.facetAngle,
                    p::facet_size = parameters.facetSize,
                    p::facet_distance = parameters.facetDistance,
                    p::cell_radius_edge_ratio = parameters.cellRadiusEdgeRatio,
                    p::cell_size = parameters.cellSize);
  }
  return Criteria(p::facet_angle = parameters.facetAngle,
                  p::facet_size = parameters.facetSize,
                  p::facet_distance = parameters.facetDistance,
                  p::cell_radius_edge_ratio = parameters.cellRadiusEdgeRatio,
                  p::cell_size = cellSize);
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
  // exudation costs several times more and adds little, so it is opt-in (docs/benchmarks.md, mesh quality).
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
