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
#include "bmrDistanceLabels.h"

#include "bmrError.h"

#include "itkGridGeometryConversion.h"
#include "itkRegionOfInterestImageFilter.h"
#include "itkSceneDistanceMaps.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <set>

namespace bmr {
namespace {

/** One label's symmetric signed distance [mm] on the index box [first, first + size) of the grid. */
struct LabelDistance
{
  std::array<std::ptrdiff_t, 3> first{};
  std::array<std::ptrdiff_t, 3> size{};
  std::vector<float>            phi;

  /** phi at grid index i; +infinity outside the box (never reached for a cell that touches the label). */
  float
  At(std::ptrdiff_t i, std::ptrdiff_t j, std::ptrdiff_t k) const
  {
    i -= first[0];
    j -= first[1];
    k -= first[2];
    if (i < 0 || j < 0 || k < 0 || i >= size[0] || j >= size[1] || k >= size[2])
    {
      return std::numeric_limits<float>::infinity();
    }
    return phi[static_cast<std::size_t>(i + size[0] * (j + size[1] * k))];
  }
};

using LabelImage = itk::Image<std::int32_t, 3>;

/** The symmetric distance of label \a value (itk::detail::MaskAndComplementMap) on the box of its voxels grown by
 * two voxels along every axis (itk::detail::PaddedMaskBox, clipped to the grid). */
LabelDistance
DistanceOfLabel(const LabelImage * labels, std::int32_t value)
{
  const auto &              spacing = labels->GetSpacing();
  const double              margin = 2.0 * std::max({ spacing[0], spacing[1], spacing[2] });
  const itk::ImageRegion<3> box = itk::detail::PaddedMaskBox(labels, value, value, margin);
  auto                      crop = itk::RegionOfInterestImageFilter<LabelImage, LabelImage>::New();
  crop->SetInput(labels);
  crop->SetRegionOfInterest(box);
  crop->Update();
  const auto    map = itk::detail::MaskAndComplementMap(crop->GetOutput(), value, value);
  LabelDistance d;
  for (unsigned a = 0; a < 3; ++a)
  {
    d.first[a] = static_cast<std::ptrdiff_t>(box.GetIndex(a));
    d.size[a] = static_cast<std::ptrdiff_t>(box.GetSize(a));
  }
  d.phi.assign(map->GetBufferPointer(), map->GetBufferPointer() + box.GetNumberOfPixels());
  return d;
}

/** What DistanceLabelFunction() returns: the grid, its labels and one distance per label present. */
class DistanceLabels
{
public:
  DistanceLabels(const std::vector<std::int32_t> & labels, const GridGeometry & grid)
    : m_Grid(grid)
    , m_Labels(labels)
  {
    const std::set<std::int32_t> present(labels.begin(), labels.end());
    m_Values.assign(present.begin(), present.end());
    const auto image = itk::MakeImageOnGrid<LabelImage>(grid, labels);
    for (std::int32_t value : m_Values)
    {
      m_Distances.push_back(DistanceOfLabel(image, value));
    }
  }

  std::int32_t
  LabelAt(double x, double y, double z) const
  {
    const std::array<double, 3>   c = m_Grid.PointToIndex({ { x, y, z } });
    std::array<std::ptrdiff_t, 3> i0;
    std::array<double, 3>         t;
    for (unsigned a = 0; a < 3; ++a)
    {
      const double last = static_cast<double>(m_Grid.size[a] - 1);
      const double ca = std::min(std::max(c[a], 0.0), last);
      i0[a] = std::min(static_cast<std::ptrdiff_t>(std::floor(ca)), static_cast<std::ptrdiff_t>(m_Grid.size[a]) - 2);
      t[a] = ca - static_cast<double>(i0[a]);
    }
    std::array<std::int32_t, 8> corner;
    for (unsigned q = 0; q < 8; ++q)
    {
      corner[q] = m_Labels[Offset(i0[0] + (q & 1), i0[1] + ((q >> 1) & 1), i0[2] + ((q >> 2) & 1))];
    }
    if (std::all_of(corner.begin(), corner.end(), [&corner](std::int32_t v) { return v == corner[0]; }))
    {
      return corner[0];
    }
    std::int32_t best = corner[0];
    double       bestPhi = std::numeric_limits<double>::infinity();
    for (unsigned q = 0; q < 8; ++q)
    {
      const double phi = Interpolate(Distance(corner[q]), i0, t);
      // Ties go to the smaller label, whatever the corner order.
      if (phi < bestPhi || (phi == bestPhi && corner[q] < best))
      {
        bestPhi = phi;
        best = corner[q];
      }
    }
    return best;
  }

private:
  std::size_t
  Offset(std::ptrdiff_t i, std::ptrdiff_t j, std::ptrdiff_t k) const
  {
    return static_cast<std::size_t>(i) +
           m_Grid.size[0] * (static_cast<std::size_t>(j) + m_Grid.size[1] * static_cast<std::size_t>(k));
  }

  const LabelDistance &
  Distance(std::int32_t value) const
  {
    const auto found = std::lower_bound(m_Values.begin(), m_Values.end(), value);
    return m_Distances[static_cast<std::size_t>(found - m_Values.begin())];
  }

  static double
  Interpolate(const LabelDistance & d, const std::array<std::ptrdiff_t, 3> & i0, const std::array<double, 3> & t)
  {
    double sum = 0.0;
    for (unsigned q = 0; q < 8; ++q)
    {
      const unsigned s[3] = { q & 1, (q >> 1) & 1, (q >> 2) & 1 };
      const double   w = (s[0] ? t[0] : 1.0 - t[0]) * (s[1] ? t[1] : 1.0 - t[1]) * (s[2] ? t[2] : 1.0 - t[2]);
      if (w > 0.0)
      {
        sum += w * static_cast<double>(d.At(i0[0] + s[0], i0[1] + s[1], i0[2] + s[2]));
      }
    }
    return sum;
  }

  GridGeometry               m_Grid;
  std::vector<std::int32_t>  m_Labels;
  std::vector<std::int32_t>  m_Values;
  std::vector<LabelDistance> m_Distances;
};

} // namespace

std::function<std::int32_t(double, double, double)>
DistanceLabelFunction(const std::vector<std::int32_t> & labels, const GridGeometry & grid)
{
  grid.Validate("label grid");
  if (labels.size() != grid.GetNumberOfVoxels() || grid.size[0] < 2 || grid.size[1] < 2 || grid.size[2] < 2)
  {
    Fail("bmr::DistanceLabelFunction",
         "the labels must hold one value per voxel of a grid with at least 2 voxels along each axis");
  }
  const auto distances = std::make_shared<const DistanceLabels>(labels, grid);
  return [distances](double x, double y, double z) { return distances->LabelAt(x, y, z); };
}

} // namespace bmr
