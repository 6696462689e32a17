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

#include "itkImage.h"
#include "itkSignedMaurerDistanceMapImageFilter.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <set>

namespace bmr {
namespace {

using MaskImage = itk::Image<unsigned char, 3>;
using MapImage = itk::Image<float, 3>;

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

/** Maurer's signed distance [mm, negative inside] of \a mask's non-zero voxels. */
MapImage::Pointer
MaurerMap(const MaskImage * mask)
{
  auto distance = itk::SignedMaurerDistanceMapImageFilter<MaskImage, MapImage>::New();
  distance->SetInput(mask);
  distance->SetUseImageSpacing(true);
  distance->SetSquaredDistance(false);
  distance->SetInsideIsPositive(false);
  distance->SetBackgroundValue(0);
  distance->Update();
  return distance->GetOutput();
}

/** The symmetric distance of label \a value on the box of its voxels grown by two voxels (clipped to the grid). */
LabelDistance
DistanceOfLabel(const std::vector<std::int32_t> & labels, const GridGeometry & grid, std::int32_t value)
{
  const std::array<std::ptrdiff_t, 3> n = { { static_cast<std::ptrdiff_t>(grid.size[0]),
                                              static_cast<std::ptrdiff_t>(grid.size[1]),
                                              static_cast<std::ptrdiff_t>(grid.size[2]) } };
  std::array<std::ptrdiff_t, 3>       lo = n, hi = { { -1, -1, -1 } };
  std::size_t                         offset = 0;
  for (std::ptrdiff_t k = 0; k < n[2]; ++k)
    for (std::ptrdiff_t j = 0; j < n[1]; ++j)
      for (std::ptrdiff_t i = 0; i < n[0]; ++i, ++offset)
      {
        if (labels[offset] == value)
        {
          const std::array<std::ptrdiff_t, 3> at = { { i, j, k } };
          for (unsigned a = 0; a < 3; ++a)
          {
            lo[a] = std::min(lo[a], at[a]);
            hi[a] = std::max(hi[a], at[a]);
          }
        }
      }
  LabelDistance       d;
  MaskImage::SizeType size;
  for (unsigned a = 0; a < 3; ++a)
  {
    d.first[a] = std::max<std::ptrdiff_t>(lo[a] - 2, 0);
    d.size[a] = std::min<std::ptrdiff_t>(hi[a] + 2, n[a] - 1) - d.first[a] + 1;
    size[a] = static_cast<itk::SizeValueType>(d.size[a]);
  }
  MaskImage::Pointer mask[2] = { MaskImage::New(), MaskImage::New() };
  for (auto & m : mask)
  {
    m->SetRegions(size);
    m->SetSpacing(grid.spacing.data());
    m->Allocate();
  }
  std::size_t b = 0;
  for (std::ptrdiff_t k = 0; k < d.size[2]; ++k)
    for (std::ptrdiff_t j = 0; j < d.size[1]; ++j)
      for (std::ptrdiff_t i = 0; i < d.size[0]; ++i, ++b)
      {
        const auto at = static_cast<std::size_t>(d.first[0] + i + n[0] * (d.first[1] + j + n[1] * (d.first[2] + k)));
        const bool inside = labels[at] == value;
        mask[0]->GetBufferPointer()[b] = inside ? 1 : 0;
        mask[1]->GetBufferPointer()[b] = inside ? 0 : 1;
      }
  const MapImage::Pointer organ = MaurerMap(mask[0]);
  const MapImage::Pointer rest = MaurerMap(mask[1]);
  d.phi.resize(b);
  for (std::size_t v = 0; v < b; ++v)
  {
    d.phi[v] = 0.5f * (organ->GetBufferPointer()[v] - rest->GetBufferPointer()[v]);
  }
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
    for (std::int32_t value : m_Values)
    {
      m_Distances.push_back(DistanceOfLabel(labels, grid, value));
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
