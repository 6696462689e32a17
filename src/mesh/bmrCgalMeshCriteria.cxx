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
// The Mesh_3 criteria of the CGAL mesher: checks of the meshing parameters, per-label and local size bounds.
#include "bmrCgalMesher.h"

#include "bmrError.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string>

namespace bmr {
namespace meshing {
namespace {
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

} // namespace

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

} // namespace meshing
} // namespace bmr
