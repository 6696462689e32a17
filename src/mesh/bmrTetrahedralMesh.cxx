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
#include "bmrTetrahedralMesh.h"

#include "bmrError.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <sstream>

namespace bmr {
namespace {
/** Local node numbers of the four faces of a positively oriented element,
 * ordered so that each face's normal (right-hand rule) points outward. */
constexpr int FaceNodes[4][3] = { { 1, 2, 3 }, { 0, 3, 2 }, { 0, 1, 3 }, { 0, 2, 1 } };

struct Vec
{
  double x, y, z;
};
Vec
Sub(const double * a, const double * b)
{
  return { a[0] - b[0], a[1] - b[1], a[2] - b[2] };
}
Vec
Cross(const Vec & a, const Vec & b)
{
  return { a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x };
}
double
Dot(const Vec & a, const Vec & b)
{
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
double
Norm(const Vec & a)
{
  return std::sqrt(Dot(a, a));
}

/** For every element face (4e + f), the neighboring element across it, or -1. Faces are grouped by their
 * smallest node (a counting sort) and matched within each group by sorting their node triples, then their face
 * numbers: the order of one global sort of the triples, without its cost, so deterministic. Equal triples are
 * paired in that order (a valid mesh has at most two). */
std::vector<std::int64_t>
FaceNeighbors(const TetrahedralMesh & mesh)
{
  const std::size_t M = mesh.GetNumberOfTetrahedra();
  struct Key
  {
    std::array<std::int32_t, 3> nodes;
    std::int64_t                face;
  };
  std::vector<Key> keys(4 * M);
  for (std::size_t e = 0; e < M; ++e)
  {
    for (int f = 0; f < 4; ++f)
    {
      Key & k = keys[4 * e + f];
      for (int i = 0; i < 3; ++i)
      {
        k.nodes[i] = mesh.tetrahedra[4 * e + FaceNodes[f][i]];
      }
      std::sort(k.nodes.begin(), k.nodes.end());
      k.face = static_cast<std::int64_t>(4 * e + f);
    }
  }
  // Counting sort by the smallest node, stable (faces ascending within a group); sized by the largest node named,
  // so that a mesh that names nodes it does not have is still answered (ValidateMesh reports it).
  std::int32_t largest = -1;
  for (const Key & k : keys)
  {
    if (k.nodes[0] < 0)
    {
      Fail("FaceNeighbors", "element " + std::to_string(k.face / 4) + " has a negative node index");
    }
    largest = std::max(largest, k.nodes[2]);
  }
  std::vector<std::size_t> start(static_cast<std::size_t>(largest) + 2, 0);
  for (const Key & k : keys)
  {
    ++start[static_cast<std::size_t>(k.nodes[0]) + 1];
  }
  for (std::size_t n = 0; n + 1 < start.size(); ++n)
  {
    start[n + 1] += start[n];
  }
  std::vector<Key>         grouped(keys.size());
  std::vector<std::size_t> next(start.begin(), start.end() - 1);
  for (const Key & k : keys)
  {
    grouped[next[static_cast<std::size_t>(k.nodes[0])]++] = k;
  }
  std::vector<std::int64_t> neighbor(4 * M, -1);
  for (std::size_t n = 0; n + 1 < start.size(); ++n)
  {
    const auto first = grouped.begin() + static_cast<std::ptrdiff_t>(start[n]);
    const auto last = grouped.begin() + static_cast<std::ptrdiff_t>(start[n + 1]);
    std::sort(first, last, [](const Key & a, const Key & b) {
      return a.nodes < b.nodes || (a.nodes == b.nodes && a.face < b.face);
    });
    for (auto k = first; k != last && k + 1 != last; ++k)
    {
      if (k->nodes == (k + 1)->nodes)
      {
        neighbor[k->face] = (k + 1)->face / 4;
        neighbor[(k + 1)->face] = k->face / 4;
        ++k;
      }
    }
  }
  return neighbor;
}

} // namespace

std::vector<std::int32_t>
UniqueNodes(std::vector<std::int32_t> nodes)
{
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  return nodes;
}

double
TetrahedronVolume(const TetrahedralMesh & mesh, std::size_t e)
{
  const std::int32_t * t = &mesh.tetrahedra[4 * e];
  const double *       x0 = &mesh.points[3 * t[0]];
  return Dot(Sub(&mesh.points[3 * t[1]], x0), Cross(Sub(&mesh.points[3 * t[2]], x0), Sub(&mesh.points[3 * t[3]], x0))) /
         6.0;
}

namespace {
/** Whether element \a e has a volume <= 0 once its nodes are moved by \a displacement. */
bool
IsInverted(const TetrahedralMesh & mesh, const std::vector<double> & displacement, std::size_t e)
{
  double x[4][3];
  for (int i = 0; i < 4; ++i)
  {
    const std::size_t n = static_cast<std::size_t>(mesh.tetrahedra[4 * e + i]);
    for (int c = 0; c < 3; ++c)
    {
      x[i][c] = mesh.points[3 * n + c] + displacement[3 * n + c];
    }
  }
  return !(Dot(Sub(x[1], x[0]), Cross(Sub(x[2], x[0]), Sub(x[3], x[0]))) > 0.0);
}

/** The labels around each node (ascending, without repeats): of the elements that hold it, and of the excluded
 * regions beyond the boundary faces that hold it (a hollow organ's lumen, a bone left out of the mesh). */
std::vector<std::vector<std::int32_t>>
LabelsAroundNodes(const TetrahedralMesh & mesh)
{
  std::vector<std::vector<std::int32_t>> around(mesh.GetNumberOfPoints());
  const auto                             add = [&around](std::int32_t node, std::int32_t label) {
    std::vector<std::int32_t> & labels = around[static_cast<std::size_t>(node)];
    if (std::find(labels.begin(), labels.end(), label) == labels.end())
    {
      labels.insert(std::upper_bound(labels.begin(), labels.end(), label), label);
    }
  };
  for (std::size_t e = 0; e < mesh.GetNumberOfTetrahedra(); ++e)
  {
    for (int i = 0; i < 4; ++i)
    {
      add(mesh.tetrahedra[4 * e + i], e < mesh.labels.size() ? mesh.labels[e] : 0);
    }
  }
  for (std::size_t f = 0; f < mesh.boundaryFaceLabels.size(); ++f)
  {
    for (int i = 0; mesh.boundaryFaceLabels[f] != 0 && i < 3; ++i) // 0: the outside of the meshed domain
    {
      add(mesh.boundaryFaces[3 * f + i], mesh.boundaryFaceLabels[f]);
    }
  }
  return around;
}

/** Throws unless \a displacement has 3 values per node of \a mesh. */
void
CheckDisplacementSize(const TetrahedralMesh & mesh, const std::vector<double> & displacement)
{
  if (displacement.size() != mesh.points.size())
  {
    Fail("CountInvertedElements",
         "the displacement holds " + std::to_string(displacement.size()) + " values, expected " +
           std::to_string(mesh.points.size()));
  }
}
} // namespace

std::map<std::int32_t, InvertedElements>
InvertedElementsByLabel(const TetrahedralMesh & mesh, const std::vector<double> & displacement)
{
  CheckDisplacementSize(mesh, displacement);
  std::map<std::int32_t, InvertedElements> inverted;
  std::vector<std::vector<std::int32_t>>   around; // made at the first inverted element only
  for (std::size_t e = 0; e < mesh.GetNumberOfTetrahedra(); ++e)
  {
    if (!IsInverted(mesh, displacement, e))
    {
      continue;
    }
    if (around.empty())
    {
      around = LabelsAroundNodes(mesh);
    }
    const std::int32_t        label = e < mesh.labels.size() ? mesh.labels[e] : 0;
    std::vector<std::int32_t> others;
    for (int i = 0; i < 4; ++i)
    {
      for (std::int32_t other : around[static_cast<std::size_t>(mesh.tetrahedra[4 * e + i])])
      {
        if (other != label && std::find(others.begin(), others.end(), other) == others.end())
        {
          others.push_back(other);
        }
      }
    }
    InvertedElements & of = inverted[label];
    ++of.count;
    for (std::int32_t other : others)
    {
      ++of.touching[other];
    }
  }
  return inverted;
}

std::string
InvertedElementsText(const std::map<std::int32_t, InvertedElements> & inverted,
                     const std::map<std::int32_t, std::string> &      names)
{
  const auto name = [&names](std::int32_t label) {
    const auto found = names.find(label);
    return found != names.end() ? found->second : "label " + std::to_string(label);
  };
  std::ostringstream text;
  for (const auto & [label, of] : inverted)
  {
    text << (text.tellp() > 0 ? "; " : "") << name(label) << ": " << of.count;
    std::size_t k = 0;
    for (const auto & [other, count] : of.touching)
    {
      text << (k == 0                        ? ", of which "
               : k + 1 == of.touching.size() ? " and "
                                             : ", ")
           << count << " against " << name(other);
      ++k;
    }
  }
  return text.str();
}

std::size_t
CountInvertedElements(const TetrahedralMesh & mesh, const std::vector<double> & displacement)
{
  // Counted alone: the estimation asks at every trial point, and where they lie is only for the report.
  CheckDisplacementSize(mesh, displacement);
  std::size_t count = 0;
  for (std::size_t e = 0; e < mesh.GetNumberOfTetrahedra(); ++e)
  {
    count += IsInverted(mesh, displacement, e) ? 1 : 0;
  }
  return count;
}

MeshQuality
ComputeMeshQuality(const TetrahedralMesh & mesh)
{
  MeshQuality       q;
  const std::size_t M = mesh.GetNumberOfTetrahedra();
  if (M == 0)
  {
    return q;
  }
  q.minimumDihedralAngleDegrees = 180.0;
  q.minimumRadiusRatio = 1.0;
  double       sumRatio = 0.0, sumEdge = 0.0;
  const double degrees = 180.0 / 3.14159265358979323846;
  for (std::size_t e = 0; e < M; ++e)
  {
    const std::int32_t * t = &mesh.tetrahedra[4 * e];
    const double *       x[4] = {
            &mesh.points[3 * t[0]], &mesh.points[3 * t[1]], &mesh.points[3 * t[2]], &mesh.points[3 * t[3]]
    };
    const double V = TetrahedronVolume(mesh, e);
    q.volume += V;
    // Outward face normals (unnormalized: length = 2 area).
    Vec    n[4];
    double area = 0.0;
    for (int f = 0; f < 4; ++f)
    {
      n[f] = Cross(Sub(x[FaceNodes[f][1]], x[FaceNodes[f][0]]), Sub(x[FaceNodes[f][2]], x[FaceNodes[f][0]]));
      area += 0.5 * Norm(n[f]);
    }
    // The dihedral angle at the edge shared by faces f and g is pi minus the angle of their outward normals.
    for (int f = 0; f < 4; ++f)
    {
      for (int g = f + 1; g < 4; ++g)
      {
        const double c = -Dot(n[f], n[g]) / (Norm(n[f]) * Norm(n[g]));
        const double angle = std::acos(std::max(-1.0, std::min(1.0, c))) * degrees;
        if (angle < q.minimumDihedralAngleDegrees)
        {
          q.minimumDihedralAngleDegrees = angle;
          q.sharpestElement = static_cast<std::int64_t>(e);
        }
        q.maximumDihedralAngleDegrees = std::max(q.maximumDihedralAngleDegrees, angle);
      }
    }
    const Vec    a = Sub(x[1], x[0]), b = Sub(x[2], x[0]), c = Sub(x[3], x[0]);
    const Vec    bc = Cross(b, c), ca = Cross(c, a), ab = Cross(a, b);
    const double a2 = Dot(a, a), b2 = Dot(b, b), c2 = Dot(c, c);
    const Vec    w{ a2 * bc.x + b2 * ca.x + c2 * ab.x,
                 a2 * bc.y + b2 * ca.y + c2 * ab.y,
                 a2 * bc.z + b2 * ca.z + c2 * ab.z };
    const double circumradius = Norm(w) / (12.0 * std::abs(V));
    const double inradius = 3.0 * std::abs(V) / area;
    const double ratio = 3.0 * inradius / circumradius;
    sumRatio += ratio;
    if (ratio < q.minimumRadiusRatio)
    {
      q.minimumRadiusRatio = ratio;
      q.worstElement = static_cast<std::int64_t>(e);
    }
    for (int i = 0; i < 4; ++i)
    {
      for (int j = i + 1; j < 4; ++j)
      {
        sumEdge += Norm(Sub(x[j], x[i]));
      }
    }
  }
  q.meanRadiusRatio = sumRatio / static_cast<double>(M);
  q.meanEdgeLength = sumEdge / (6.0 * static_cast<double>(M));
  return q;
}

void
ValidateMesh(const TetrahedralMesh & mesh)
{
  const std::size_t N = mesh.GetNumberOfPoints();
  const std::size_t M = mesh.GetNumberOfTetrahedra();
  if (mesh.points.size() != 3 * N || mesh.tetrahedra.size() != 4 * M)
  {
    Fail("ValidateMesh", "points must hold 3 and tetrahedra 4 values per entry, one label per tetrahedron");
  }
  if (M == 0)
  {
    Fail("ValidateMesh", "the mesh has no element");
  }
  for (std::size_t k = 0; k < mesh.points.size(); ++k)
  {
    if (!std::isfinite(mesh.points[k]))
    {
      Fail("ValidateMesh", "node " + std::to_string(k / 3) + " has a non-finite coordinate");
    }
  }
  double edge = 0.0;
  for (std::size_t e = 0; e < M; ++e)
  {
    for (int a = 0; a < 4; ++a)
    {
      const std::int32_t n = mesh.tetrahedra[4 * e + a];
      if (n < 0 || static_cast<std::size_t>(n) >= N)
      {
        std::ostringstream msg;
        msg << "element " << e << " refers to node " << n << ", outside the " << N << " nodes";
        Fail("ValidateMesh", msg.str());
      }
    }
    const double * x0 = &mesh.points[3 * mesh.tetrahedra[4 * e]];
    const double * x1 = &mesh.points[3 * mesh.tetrahedra[4 * e + 1]];
    edge = std::max(edge, Norm(Sub(x1, x0)));
  }
  // An element whose volume is below 1e-12 of the largest edge cubed is degenerate to rounding.
  const double tiny = 1e-12 * edge * edge * edge;
  for (std::size_t e = 0; e < M; ++e)
  {
    const double V = TetrahedronVolume(mesh, e);
    if (!(V > tiny))
    {
      std::ostringstream msg;
      msg << "element " << e << " (label " << mesh.labels[e] << ") is " << (V < 0 ? "inverted" : "degenerate")
          << ": volume " << V << " mm^3";
      Fail("ValidateMesh", msg.str());
    }
  }
}

TetrahedralMesh
ExtractSubmesh(const TetrahedralMesh & full, const std::vector<std::int32_t> & excluded)
{
  const std::size_t M = full.GetNumberOfTetrahedra();
  auto              isExcluded = [&excluded](std::int32_t label) {
    return std::find(excluded.begin(), excluded.end(), label) != excluded.end();
  };
  const std::vector<std::int64_t> neighbor = FaceNeighbors(full);
  std::vector<std::int32_t>       newNode(full.GetNumberOfPoints(), -1);
  TetrahedralMesh                 out;
  std::int32_t                    count = 0;
  for (std::size_t e = 0; e < M; ++e)
  {
    if (isExcluded(full.labels[e]))
    {
      continue;
    }
    for (int a = 0; a < 4; ++a)
    {
      const std::int32_t n = full.tetrahedra[4 * e + a];
      if (newNode[n] < 0)
      {
        newNode[n] = 0; // mark; numbered below in original order
      }
    }
  }
  for (std::size_t n = 0; n < newNode.size(); ++n)
  {
    if (newNode[n] == 0)
    {
      newNode[n] = count++;
      out.points.insert(out.points.end(), &full.points[3 * n], &full.points[3 * n + 3]);
    }
  }
  for (std::size_t e = 0; e < M; ++e)
  {
    if (isExcluded(full.labels[e]))
    {
      continue;
    }
    for (int a = 0; a < 4; ++a)
    {
      out.tetrahedra.push_back(newNode[full.tetrahedra[4 * e + a]]);
    }
    out.labels.push_back(full.labels[e]);
    for (int f = 0; f < 4; ++f)
    {
      const std::int64_t other = neighbor[4 * e + f];
      std::int32_t       beyond;
      if (other < 0)
      {
        beyond = 0;
      }
      else if (isExcluded(full.labels[other]))
      {
        beyond = full.labels[other];
      }
      else
      {
        continue;
      }
      for (int i = 0; i < 3; ++i)
      {
        out.boundaryFaces.push_back(newNode[full.tetrahedra[4 * e + FaceNodes[f][i]]]);
      }
      out.boundaryFaceLabels.push_back(beyond);
    }
  }
  if (out.labels.empty())
  {
    Fail("ExtractSubmesh", "every element was excluded: no label is left to simulate");
  }
  return out;
}

std::vector<std::int32_t>
NodesOnBoundary(const TetrahedralMesh & mesh, std::int32_t label)
{
  std::vector<std::int32_t> faces;
  for (std::size_t f = 0; f < mesh.boundaryFaceLabels.size(); ++f)
  {
    if (mesh.boundaryFaceLabels[f] == label)
    {
      faces.insert(faces.end(), &mesh.boundaryFaces[3 * f], &mesh.boundaryFaces[3 * f + 3]);
    }
  }
  return UniqueNodes(faces);
}

// Only the label's own elements are matched (the prostate's are about a tenth of the pelvis's): a face of the label
// lies on its surface when no other element of the label shares it, i.e. when its neighbor has another label or
// there is none.
std::vector<std::int32_t>
LabelSurfaceFaces(const TetrahedralMesh & mesh, std::int32_t label)
{
  TetrahedralMesh          own; // the label's elements, their nodes keeping their numbers
  std::vector<std::size_t> element;
  for (std::size_t e = 0; e < mesh.GetNumberOfTetrahedra(); ++e)
  {
    if (mesh.labels[e] == label)
    {
      own.tetrahedra.insert(own.tetrahedra.end(), &mesh.tetrahedra[4 * e], &mesh.tetrahedra[4 * e] + 4);
      own.labels.push_back(label);
      element.push_back(e);
    }
  }
  const std::vector<std::int64_t> neighbor = FaceNeighbors(own);
  std::vector<std::int32_t>       faces;
  for (std::size_t k = 0; k < element.size(); ++k)
  {
    for (int f = 0; f < 4; ++f)
    {
      if (neighbor[4 * k + f] < 0)
      {
        for (int i = 0; i < 3; ++i)
        {
          faces.push_back(mesh.tetrahedra[4 * element[k] + FaceNodes[f][i]]);
        }
      }
    }
  }
  return faces;
}

std::vector<std::int32_t>
NodesOnLabelSurface(const TetrahedralMesh & mesh, std::int32_t label)
{
  return UniqueNodes(LabelSurfaceFaces(mesh, label));
}

std::vector<LabelResolution>
ComputeLabelResolution(const TetrahedralMesh & mesh)
{
  // One pass over the elements: volume, edges, and the faces whose neighbor has another label (or none).
  const std::vector<std::int64_t>         neighbor = FaceNeighbors(mesh);
  std::map<std::int32_t, LabelResolution> byLabel;
  std::map<std::int32_t, std::size_t>     elements;
  for (std::size_t e = 0; e < mesh.GetNumberOfTetrahedra(); ++e)
  {
    const std::int32_t * t = &mesh.tetrahedra[4 * e];
    const double *       x[4] = {
            &mesh.points[3 * t[0]], &mesh.points[3 * t[1]], &mesh.points[3 * t[2]], &mesh.points[3 * t[3]]
    };
    LabelResolution & r = byLabel[mesh.labels[e]];
    r.label = mesh.labels[e];
    r.volume += std::abs(TetrahedronVolume(mesh, e));
    for (int i = 0; i < 4; ++i)
    {
      for (int j = i + 1; j < 4; ++j)
      {
        r.meanEdgeLength += Norm(Sub(x[j], x[i]));
      }
    }
    for (int f = 0; f < 4; ++f)
    {
      const std::int64_t other = neighbor[4 * e + f];
      if (other < 0 || mesh.labels[other] != mesh.labels[e])
      {
        r.surfaceArea +=
          0.5 * Norm(Cross(Sub(x[FaceNodes[f][1]], x[FaceNodes[f][0]]), Sub(x[FaceNodes[f][2]], x[FaceNodes[f][0]])));
      }
    }
    ++elements[mesh.labels[e]];
  }
  std::vector<LabelResolution> result;
  for (auto & kv : byLabel)
  {
    LabelResolution & r = kv.second;
    r.meanEdgeLength /= 6.0 * static_cast<double>(elements[kv.first]);
    r.elementsAcross =
      r.surfaceArea > 0.0 && r.meanEdgeLength > 0.0 ? 2.0 * r.volume / (r.surfaceArea * r.meanEdgeLength) : 0.0;
    result.push_back(r);
  }
  return result;
}

std::size_t
ConnectedComponents(const TetrahedralMesh & mesh, std::vector<std::int32_t> * componentOfNode)
{
  const std::size_t         N = mesh.GetNumberOfPoints();
  std::vector<std::int32_t> parent(N);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&parent](std::int32_t a) {
    while (parent[a] != a)
    {
      parent[a] = parent[parent[a]];
      a = parent[a];
    }
    return a;
  };
  for (std::size_t e = 0; e < mesh.GetNumberOfTetrahedra(); ++e)
  {
    std::int32_t r0 = find(mesh.tetrahedra[4 * e]);
    for (int a = 1; a < 4; ++a)
    {
      const std::int32_t ra = find(mesh.tetrahedra[4 * e + a]);
      if (ra != r0)
      {
        // Attach the larger root to the smaller so that the numbering does not depend on the visiting order.
        parent[std::max(ra, r0)] = std::min(ra, r0);
        r0 = std::min(ra, r0);
      }
    }
  }
  std::vector<std::int32_t> id(N, -1), comp(N);
  std::int32_t              count = 0;
  for (std::size_t n = 0; n < N; ++n)
  {
    const std::int32_t r = find(static_cast<std::int32_t>(n));
    if (id[r] < 0)
    {
      id[r] = count++;
    }
    comp[n] = id[r];
  }
  if (componentOfNode)
  {
    *componentOfNode = std::move(comp);
  }
  return static_cast<std::size_t>(count);
}

} // namespace bmr
