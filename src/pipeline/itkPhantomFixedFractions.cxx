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
// The phantom's fixed organs as sub-voxel data: volume fractions (a partial-volume segmentation) and the area
// fractions of their exact outlines on each slice (an RTSTRUCT drawn on the fixed scan).
#include "itkPipelineStages.h"

#include "itkGridGeometryConversion.h"
#include "itkPlanarContourFractions.h"
#include "itkVectorLinearInterpolateImageFunction.h"

#include <array>

namespace itk {
namespace pipeline {
namespace {

/** The points of the analytic anatomy that the fixed points at continuous \a indices of \a labels' grid come from:
 * each index's physical point plus the truth's pull-back displacement there (trilinear between voxel centres), as
 * x, y, z triples for PhantomLabelsAt. */
std::vector<double>
PulledBack(const BiomechanicalLabelImageType *             labels,
           const BiomechanicalFieldType *                  field,
           const std::vector<ContinuousIndex<double, 3>> & indices)
{
  auto interpolator = VectorLinearInterpolateImageFunction<BiomechanicalFieldType, double>::New();
  interpolator->SetInputImage(field);
  std::vector<double> points;
  points.reserve(3 * indices.size());
  for (const auto & index : indices)
  {
    Point<double, 3> x;
    labels->TransformContinuousIndexToPhysicalPoint(index, x);
    const auto d = interpolator->IsInsideBuffer(index) ? interpolator->EvaluateAtContinuousIndex(index)
                                                       : field->GetPixel(labels->GetLargestPossibleRegion().GetIndex());
    for (unsigned int c = 0; c < 3; ++c)
    {
      points.push_back(x[c] + d[c]);
    }
  }
  return points;
}

/** The voxels of \a labels with a 26-neighbour of another label (those a sub-voxel surface can cross). */
std::vector<std::size_t>
MixedVoxels(const BiomechanicalLabelImageType * labels)
{
  const bmr::GridGeometry  grid = GridGeometryOf(labels);
  const std::int32_t *     l = labels->GetBufferPointer();
  std::vector<std::size_t> mixed;
  for (std::size_t v = 0; v < grid.GetNumberOfVoxels(); ++v)
  {
    const std::array<long, 3> i{
      { long(v % grid.size[0]), long((v / grid.size[0]) % grid.size[1]), long(v / (grid.size[0] * grid.size[1])) }
    };
    bool uniform = true;
    for (int n = 0; n < 27 && uniform; ++n)
    {
      const std::array<long, 3> j{ { i[0] + n % 3 - 1, i[1] + n / 3 % 3 - 1, i[2] + n / 9 - 1 } };
      if (j[0] >= 0 && j[1] >= 0 && j[2] >= 0 && j[0] < long(grid.size[0]) && j[1] < long(grid.size[1]) &&
          j[2] < long(grid.size[2]))
      {
        uniform = l[(j[2] * grid.size[1] + j[1]) * grid.size[0] + j[0]] == l[v];
      }
    }
    if (!uniform)
    {
      mixed.push_back(v);
    }
  }
  return mixed;
}

/** One outline vertex being moved onto the anatomy's boundary: the voxel-edge ends inside and outside the organ. */
struct EdgeBracket
{
  ContinuousIndex<double, 3> inside, outside;
};

/** Marching squares puts each vertex halfway along a voxel edge (one coordinate a half-integer) between a voxel of
 * the organ and one without: the bracket of that edge. */
EdgeBracket
BracketOf(const BiomechanicalLabelImageType * labels, std::int32_t value, double x, double y, long k)
{
  const bool                 alongX = std::abs(x - std::round(x)) > 0.25;
  ContinuousIndex<double, 3> a, b;
  a[0] = alongX ? x - 0.5 : x;
  a[1] = alongX ? y : y - 0.5;
  b[0] = alongX ? x + 0.5 : x;
  b[1] = alongX ? y : y + 0.5;
  a[2] = b[2] = double(k);
  const auto & size = labels->GetLargestPossibleRegion().GetSize();
  const auto   in = [&](const ContinuousIndex<double, 3> & c) {
    const long i = std::lround(c[0]), j = std::lround(c[1]);
    return i >= 0 && j >= 0 && i < long(size[0]) && j < long(size[1]) &&
           labels->GetBufferPointer()[(std::size_t(k) * size[1] + std::size_t(j)) * size[0] + std::size_t(i)] == value;
  };
  return in(a) ? EdgeBracket{ a, b } : EdgeBracket{ b, a };
}

/** Halves every bracket \a halvings times against the anatomy (\a labelsAt of the pulled-back midpoints). */
void
Bisect(std::vector<EdgeBracket> &          brackets,
       std::int32_t                        value,
       const BiomechanicalLabelImageType * labels,
       const BiomechanicalFieldType *      field,
       const AnatomyLabelsFunction &       labelsAt,
       unsigned int                        halvings)
{
  std::vector<ContinuousIndex<double, 3>> middles(brackets.size());
  for (unsigned int h = 0; h < halvings; ++h)
  {
    for (std::size_t b = 0; b < brackets.size(); ++b)
    {
      for (unsigned int a = 0; a < 3; ++a)
      {
        middles[b][a] = 0.5 * (brackets[b].inside[a] + brackets[b].outside[a]);
      }
    }
    const std::vector<std::int32_t> at = labelsAt(PulledBack(labels, field, middles));
    for (std::size_t b = 0; b < brackets.size(); ++b)
    {
      (at[b] == value ? brackets[b].inside : brackets[b].outside) = middles[b];
    }
  }
}

} // namespace

OrganProbabilityImages
FixedVolumeFractions(const bmr::Scene &                  scene,
                     const BiomechanicalLabelImageType * labels,
                     const BiomechanicalFieldType *      field,
                     const AnatomyLabelsFunction &       labelsAt)
{
  const bmr::GridGeometry                 grid = GridGeometryOf(labels);
  const std::vector<std::size_t>          mixed = MixedVoxels(labels);
  constexpr int                           sub = 4;
  std::vector<ContinuousIndex<double, 3>> indices;
  indices.reserve(mixed.size() * sub * sub * sub);
  for (std::size_t v : mixed)
  {
    const std::size_t i[3] = { v % grid.size[0], (v / grid.size[0]) % grid.size[1], v / (grid.size[0] * grid.size[1]) };
    for (int k = 0; k < sub * sub * sub; ++k)
    {
      ContinuousIndex<double, 3> index;
      index[0] = double(i[0]) + (k % sub + 0.5) / sub - 0.5;
      index[1] = double(i[1]) + (k / sub % sub + 0.5) / sub - 0.5;
      index[2] = double(i[2]) + (k / (sub * sub) + 0.5) / sub - 0.5;
      indices.push_back(index);
    }
  }
  const std::vector<std::int32_t> subLabels = labelsAt(PulledBack(labels, field, indices));
  const std::int32_t *            l = labels->GetBufferPointer();
  OrganProbabilityImages          fractions;
  for (const bmr::ObjectiveTerm & term : scene.objective)
  {
    const std::int32_t value = scene.FindLabel(term.label)->value;
    std::vector<float> f(grid.GetNumberOfVoxels());
    for (std::size_t v = 0; v < f.size(); ++v)
    {
      f[v] = l[v] == value ? 1.0f : 0.0f;
    }
    for (std::size_t m = 0; m < mixed.size(); ++m)
    {
      int in = 0;
      for (int k = 0; k < sub * sub * sub; ++k)
      {
        in += subLabels[m * sub * sub * sub + k] == value;
      }
      f[mixed[m]] = float(in) / float(sub * sub * sub);
    }
    fractions[term.label] = MakeImageOnGrid<BiomechanicalProbabilityImageType>(grid, f);
  }
  return fractions;
}

OrganProbabilityImages
FixedContourFractions(const bmr::Scene &                  scene,
                      const BiomechanicalLabelImageType * labels,
                      const BiomechanicalFieldType *      field,
                      const AnatomyLabelsFunction &       labelsAt)
{
  constexpr unsigned int halvings = 12; // 1/4096 of a voxel: far below what the outlines' chords differ by
  const long             slices = long(labels->GetLargestPossibleRegion().GetSize(2));
  OrganProbabilityImages fractions;
  for (const bmr::ObjectiveTerm & term : scene.objective)
  {
    const std::int32_t       value = scene.FindLabel(term.label)->value;
    std::vector<EdgeBracket> brackets;
    std::vector<std::size_t> ringEnds; // brackets[ringEnds[r - 1] .. ringEnds[r]) form ring r
    for (long k = 0; k < slices; ++k)
    {
      for (const auto & ring : LabelOutlinesOnSlice(labels, value, k))
      {
        for (const auto & vertex : ring)
        {
          brackets.push_back(BracketOf(labels, value, vertex[0], vertex[1], k));
        }
        ringEnds.push_back(brackets.size());
      }
    }
    Bisect(brackets, value, labels, field, labelsAt, halvings);
    std::vector<PlanarContour> contours;
    for (std::size_t r = 0, begin = 0; r < ringEnds.size(); begin = ringEnds[r++])
    {
      PlanarContour contour;
      for (std::size_t b = begin; b < ringEnds[r]; ++b)
      {
        ContinuousIndex<double, 3> middle;
        for (unsigned int a = 0; a < 3; ++a)
        {
          middle[a] = 0.5 * (brackets[b].inside[a] + brackets[b].outside[a]);
        }
        contour.points.emplace_back();
        labels->TransformContinuousIndexToPhysicalPoint(middle, contour.points.back());
      }
      if (contour.points.size() >= 3)
      {
        contours.push_back(std::move(contour));
      }
    }
    fractions[term.label] =
      PlanarContourAreaFractions(contours, labels, "the phantom's fixed outlines of \"" + term.label + "\"");
  }
  return fractions;
}

} // namespace pipeline
} // namespace itk
