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
// Planar contours on a grid: their edges per slice (the RTSTRUCT reader's even-odd fill uses them too) and the area
// fraction of each voxel they enclose.
#include "itkPlanarContours.h"

#include "bmrError.h"
#include "itkContourExtractor2DImageFilter.h"
#include "itkImageRegionConstIteratorWithIndex.h"
#include "itkGridGeometryConversion.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace itk {
namespace detail {

std::map<long, std::vector<ContourEdge>>
ContourEdgesPerSlice(const std::vector<PlanarContour> & contours,
                     const ImageBase<3> *               grid,
                     const char *                       where,
                     const std::string &                owner)
{
  // Continuous indices are computed by the grid (any direction), relative to its region's start.
  const auto region = grid->GetLargestPossibleRegion();
  // DS values carry at most 16 characters: positions are exact to ~1e-6 of a voxel; 1e-3 voxel is ample.
  constexpr double                         tolerance = 1e-3;
  std::map<long, std::vector<ContourEdge>> edges;
  for (std::size_t c = 0; c < contours.size(); ++c)
  {
    const auto &      points = contours[c].points;
    const std::string what = owner + ", contour " + std::to_string(c + 1);
    const bool        finite = std::all_of(points.begin(), points.end(), [](const ImageBase<3>::PointType & p) {
      return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
    });
    if (points.size() < 3 || !finite)
    {
      bmr::Fail(where, what + " has fewer than 3 points or a coordinate that is not a finite number");
    }
    std::vector<ContinuousIndex<double, 3>> indices(points.size());
    double                                  meanK = 0.0;
    for (std::size_t p = 0; p < points.size(); ++p)
    {
      grid->TransformPhysicalPointToContinuousIndex(points[p], indices[p]);
      for (unsigned int a = 0; a < 3; ++a)
      {
        indices[p][a] -= static_cast<double>(region.GetIndex(a));
      }
      meanK += indices[p][2] / static_cast<double>(points.size());
    }
    const long         slice = std::lround(meanK);
    std::ostringstream at;
    at << " (at z = " << points.front()[2] << " mm)";
    for (const auto & index : indices)
    {
      if (std::abs(index[2] - static_cast<double>(slice)) > 0.5 + tolerance)
      {
        bmr::Fail(where,
                  what + at.str() + " does not lie in one slice of the reference grid (it is not parallel to them)");
      }
    }
    if (slice < 0 || slice >= static_cast<long>(region.GetSize(2)))
    {
      std::ostringstream os;
      os << what << at.str() << " lies on no slice of the reference grid (slice index " << meanK << ", grid 0.."
         << region.GetSize(2) - 1 << ")";
      bmr::Fail(where, os.str());
    }
    for (const auto & index : indices)
    {
      for (unsigned int a = 0; a < 2; ++a)
      {
        if (index[a] < -0.5 - tolerance || index[a] > static_cast<double>(region.GetSize(a)) - 0.5 + tolerance)
        {
          bmr::Fail(where, what + at.str() + " lies outside the reference grid in-plane");
        }
      }
    }
    auto & sliceEdges = edges[slice];
    for (std::size_t p = 0; p < indices.size(); ++p)
    {
      const auto & a = indices[p];
      const auto & b = indices[(p + 1) % indices.size()]; // closed: the last point joins the first
      sliceEdges.push_back({ a[0], a[1], b[0], b[1] });
    }
  }
  return edges;
}

void
RowCrossings(const std::vector<ContourEdge> & edges, double y, std::vector<double> & crossings)
{
  crossings.clear();
  for (const auto & e : edges)
  {
    if ((e.y0 > y) != (e.y1 > y))
    {
      crossings.push_back(e.x0 + (y - e.y0) * (e.x1 - e.x0) / (e.y1 - e.y0));
    }
  }
  std::sort(crossings.begin(), crossings.end());
}

} // namespace detail

namespace {

/** Adds to \a row (the slice's voxels i = 0..n-1 of one row) \a weight times the length of [x0, x1] within each
 * voxel's [i - 1/2, i + 1/2]. */
void
AddCoveredLengths(double x0, double x1, double weight, float * row, long n)
{
  const long first = std::max(0L, static_cast<long>(std::floor(x0 + 0.5)));
  const long last = std::min(n - 1, static_cast<long>(std::floor(x1 + 0.5)));
  for (long i = first; i <= last; ++i)
  {
    const double covered = std::min(x1, i + 0.5) - std::max(x0, i - 0.5);
    if (covered > 0.0)
    {
      row[i] += static_cast<float>(weight * covered);
    }
  }
}

} // namespace

std::vector<std::vector<std::array<double, 2>>>
LabelOutlinesOnSlice(const Image<std::int32_t, 3> * labels, std::int32_t value, IndexValueType k)
{
  using SliceImageType = Image<float, 2>;
  const auto &               region = labels->GetLargestPossibleRegion();
  SliceImageType::RegionType padded;
  for (unsigned int a = 0; a < 2; ++a)
  {
    padded.SetIndex(a, region.GetIndex(a) - 1);
    padded.SetSize(a, region.GetSize(a) + 2);
  }
  auto slice = SliceImageType::New();
  slice->SetRegions(padded);
  slice->Allocate(true);
  bool           any = false;
  ImageRegion<3> plane = region;
  plane.SetIndex(2, k);
  plane.SetSize(2, 1);
  for (ImageRegionConstIteratorWithIndex<Image<std::int32_t, 3>> it(labels, plane); !it.IsAtEnd(); ++it)
  {
    if (it.Get() == value)
    {
      slice->SetPixel({ { it.GetIndex()[0], it.GetIndex()[1] } }, 1.0f);
      any = true;
    }
  }
  std::vector<std::vector<std::array<double, 2>>> rings;
  if (!any)
  {
    return rings;
  }
  auto extractor = ContourExtractor2DImageFilter<SliceImageType>::New();
  extractor->SetInput(slice);
  extractor->SetContourValue(0.5);
  extractor->Update();
  for (unsigned int c = 0; c < extractor->GetNumberOfIndexedOutputs(); ++c)
  {
    std::vector<std::array<double, 2>> ring;
    for (const auto & v : *extractor->GetOutput(c)->GetVertexList())
    {
      ring.push_back({ { v[0], v[1] } });
    }
    if (ring.size() > 1 && ring.front() == ring.back())
    {
      ring.pop_back();
    }
    rings.push_back(std::move(ring));
  }
  return rings;
}

ContourFractionImageType::Pointer
PlanarContourAreaFractions(const std::vector<PlanarContour> & contours,
                           const ImageBase<3> *               referenceGrid,
                           const std::string &                what)
{
  constexpr const char * where = "PlanarContourAreaFractions";
  if (!referenceGrid)
  {
    bmr::Fail(where, what + ": no reference grid given");
  }
  auto fractions = MakeImageOnGrid<ContourFractionImageType>(GridGeometryOf(referenceGrid), {});
  fractions->FillBuffer(0.0f);
  const auto          region = referenceGrid->GetLargestPossibleRegion();
  const long          nx = static_cast<long>(region.GetSize(0)), ny = static_cast<long>(region.GetSize(1));
  const double        weight = 1.0 / SubRowsPerVoxel;
  std::vector<double> crossings;
  for (const auto & [slice, edges] : detail::ContourEdgesPerSlice(contours, referenceGrid, where, what))
  {
    for (long j = 0; j < ny; ++j)
    {
      float * row =
        fractions->GetBufferPointer() + static_cast<std::size_t>(nx) * static_cast<std::size_t>(j + ny * slice);
      for (unsigned int s = 0; s < SubRowsPerVoxel; ++s)
      {
        detail::RowCrossings(edges, j - 0.5 + (s + 0.5) * weight, crossings);
        for (std::size_t m = 0; m + 1 < crossings.size(); m += 2)
        {
          AddCoveredLengths(crossings[m], crossings[m + 1], weight, row, nx);
        }
      }
      for (long i = 0; i < nx; ++i)
      {
        row[i] = std::min(row[i], 1.0f); // rounding of the sums, never more than a voxel
      }
    }
  }
  return fractions;
}

} // namespace itk
