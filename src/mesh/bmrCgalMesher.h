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
// The CGAL types and the meshing criteria shared by the units of the CGAL mesher (private to src/mesh).
#ifndef bmrCgalMesher_h
#define bmrCgalMesher_h

#include "bmrMesher.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Labeled_mesh_domain_3.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_constant_domain_field_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace bmr {
namespace meshing {

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

/** Refuses, naming \a where, parameters outside the ranges in which Mesh_3 is known to terminate or that are not
 * positive and finite. */
void
CheckParameters(const char * where, const MeshingParameters & parameters);

/** The Mesh_3 criteria of \a parameters; the local refinement (MeshingParameters::refineNearLabels) is found on
 * \a lattice, which must outlive the criteria. */
Criteria
MakeCriteria(const MeshingParameters & parameters, const SampleLattice & lattice);

} // namespace meshing
} // namespace bmr

#endif
