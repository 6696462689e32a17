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
#ifndef itkSliceInterpolation_h
#define itkSliceInterpolation_h

#include "itkImage.h"
#include "itkSignedMaurerDistanceMapImageFilter.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <vector>

namespace itk {

/** Thick slices: the largest voxel side is at least this many times each of the two others. Clinical planning CTs
 * (0.9-1.2 mm in-plane, 2-3 mm slices) have them; the 1 mm phantoms and mildly anisotropic grids do not. */
constexpr double SliceInterpolationMinimumRatio = 1.5;

/** The slice axis of a grid with thick slices and how many fine slices each slice step is cut into. */
struct SliceInterpolationGeometry
{
  int          axis{ -1 };  ///< image axis of the thick slices; -1: the slices are not thick
  unsigned int factor{ 1 }; ///< m = round(slice spacing / finest in-plane spacing)
};

/** The thick-slice axis of \a image (SliceInterpolationMinimumRatio), or axis -1 when it has none. */
template<typename TImage>
SliceInterpolationGeometry
ThickSlices(const TImage * image)
{
  const auto & spacing = image->GetSpacing();
  unsigned int thick = 0;
  for (unsigned int a = 1; a < 3; ++a)
  {
    thick = spacing[a] > spacing[thick] ? a : thick;
  }
  double finest = NumericTraits<double>::max(), coarsest = 0.0; // in-plane
  for (unsigned int a = 0; a < 3; ++a)
  {
    finest = a == thick ? finest : std::min(finest, double(spacing[a]));
    coarsest = a == thick ? coarsest : std::max(coarsest, double(spacing[a]));
  }
  SliceInterpolationGeometry g;
  if (spacing[thick] >= SliceInterpolationMinimumRatio * coarsest &&
      image->GetLargestPossibleRegion().GetSize(thick) >= 2)
  {
    g.axis = static_cast<int>(thick);
    g.factor = static_cast<unsigned int>(std::lround(spacing[thick] / finest));
  }
  return g;
}

namespace detail {
/** The in-plane signed distance [mm, negative inside] of one slice's mask (\a nx x \a ny, x fastest) to the faces of
 * its pixels: Maurer's map of the mask and of its complement, averaged, as MaskAndComplementMap() in 3-D. The mask
 * must hold both values. */
inline std::vector<float>
SliceFaceDistance(const std::vector<unsigned char> & mask, std::size_t nx, std::size_t ny, double sx, double sy)
{
  using MaskType = Image<unsigned char, 2>;
  using MapType = Image<float, 2>;
  std::vector<float> phi(mask.size(), 0.0f);
  for (int complement = 0; complement < 2; ++complement)
  {
    auto               image = MaskType::New();
    MaskType::SizeType size = { { nx, ny } };
    image->SetRegions(size);
    const double spacing[2] = { sx, sy };
    image->SetSpacing(spacing);
    image->Allocate();
    unsigned char * out = image->GetBufferPointer();
    for (std::size_t p = 0; p < mask.size(); ++p)
    {
      out[p] = static_cast<unsigned char>(complement ? !mask[p] : mask[p]);
    }
    auto distance = SignedMaurerDistanceMapImageFilter<MaskType, MapType>::New();
    distance->SetInput(image);
    distance->SetUseImageSpacing(true);
    distance->SetSquaredDistance(false);
    distance->SetInsideIsPositive(false);
    distance->SetBackgroundValue(0);
    distance->Update();
    const float * map = distance->GetOutput()->GetBufferPointer();
    for (std::size_t p = 0; p < mask.size(); ++p)
    {
      phi[p] += complement ? -0.5f * map[p] : 0.5f * map[p];
    }
  }
  return phi;
}

/** One label's in-plane distance on one slice, with what the interpolation needs of a slice it does not cross. */
struct SliceLabelMap
{
  std::vector<float> phi;              ///< in-plane face distance [mm]; empty when the slice has no boundary
  bool               present{ false }; ///< the label occurs in the slice
  float              deepest{ 0.0f };  ///< largest distance inside [mm]
  float              farthest{ 0.0f }; ///< largest distance outside [mm]
};
} // namespace detail

/** \brief Shape-based interpolation of a label map between its thick slices.
 *
 * A label map of a CT with thick slices (2-3 mm against 1 mm in-plane) samples each organ's cross-section on every
 * slice and says nothing between: its voxel faces make a staircase of slice-thick terraces, and two scans of the
 * same anatomy on grids a fraction of a slice apart disagree by up to a slice there. The organ's cross-sections are
 * known far better than that, so between slices they are interpolated, as planning systems interpolate contours
 * (shape-based interpolation, Raya and Udupa 1990; Herman, Zheng and Bucholtz 1992): for every label l the
 * in-plane signed distance \f$ \phi_{l,s}(p) \f$ to the faces of its pixels on slice s (detail::SliceFaceDistance)
 * is interpolated linearly along the slice axis, \f$ \phi_l(p, s + t) = (1 - t)\, \phi_{l,s}(p) + t\, \phi_{l,s+1}(p)
 * \f$, and every voxel of a grid refined m times along that axis takes the label of least \f$ \phi_l \f$. On a slice
 * without the label, \f$ \phi_l \f$ is the deepest distance inside of its neighbouring slices' cross-sections, so an
 * organ's end is a dome that reaches half a slice beyond its last cross-section at its deepest point and ends at
 * the cross-section's rim (the midpoint, on average, of where a convex organ's tip lies between two slices); on a
 * slice the label fills, minus the farthest distance outside of its neighbours'.
 *
 * The output grid has the input's origin, direction and in-plane spacing, the slice axis's spacing divided by m =
 * ThickSlices().factor and (n - 1) m + 1 voxels along it: fine slice m s is input slice s, whose labels it keeps
 * exactly. Returns \a labels itself when its slices are not thick (ThickSlices()). Deterministic: every voxel
 * depends on its two slices only. Memory: four slices' maps per label at a time.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationScene */
template<typename TLabelImage>
typename TLabelImage::ConstPointer
InterpolateLabelSlices(const TLabelImage * labels)
{
  using PixelType = typename TLabelImage::PixelType;
  const SliceInterpolationGeometry g = ThickSlices(labels);
  if (g.axis < 0 || g.factor < 2)
  {
    return labels;
  }
  const unsigned int a = static_cast<unsigned int>(g.axis);
  const unsigned int b = a == 0 ? 1 : 0, c = a == 2 ? 1 : 2; // the in-plane axes, in order
  const auto         region = labels->GetLargestPossibleRegion();
  const std::size_t  n[3] = { region.GetSize(0), region.GetSize(1), region.GetSize(2) };
  const std::size_t  stride[3] = { 1, n[0], n[0] * n[1] };
  const std::size_t  slices = n[a], pixels = n[b] * n[c];
  const PixelType *  in = labels->GetBufferPointer();
  // Voxel (p, s) of slice s, p = i_b + n_b i_c in-plane.
  const auto offset = [&](std::size_t p, std::size_t s) {
    return (p % n[b]) * stride[b] + (p / n[b]) * stride[c] + s * stride[a];
  };
  std::vector<std::set<PixelType>> present(slices);
  for (std::size_t s = 0; s < slices; ++s)
  {
    for (std::size_t p = 0; p < pixels; ++p)
    {
      present[s].insert(in[offset(p, s)]);
    }
  }
  // The maps of slices s - 1 .. s + 2 for the labels of the interval (s, s + 1), computed once each.
  std::map<std::pair<std::size_t, PixelType>, detail::SliceLabelMap> cache;
  const auto                                                         sliceMap = [&](std::size_t s, PixelType l) {
    const auto key = std::make_pair(s, l);
    const auto found = cache.find(key);
    if (found != cache.end())
    {
      return &found->second;
    }
    detail::SliceLabelMap m;
    m.present = present[s].count(l) > 0;
    if (m.present && present[s].size() > 1)
    {
      std::vector<unsigned char> mask(pixels);
      for (std::size_t p = 0; p < pixels; ++p)
      {
        mask[p] = in[offset(p, s)] == l;
      }
      m.phi = detail::SliceFaceDistance(mask, n[b], n[c], labels->GetSpacing()[b], labels->GetSpacing()[c]);
      for (float v : m.phi)
      {
        m.deepest = std::max(m.deepest, -v);
        m.farthest = std::max(m.farthest, v);
      }
    }
    return &cache.emplace(key, std::move(m)).first->second;
  };
  // phi_l on slice s: its map, or for a slice the label does not cross its neighbours' extreme distance.
  struct SliceValues
  {
    const float * phi;
    float         constant;
  };
  constexpr float far = 1e20f;
  const auto      values = [&](std::size_t s, PixelType l) {
    const detail::SliceLabelMap * map = sliceMap(s, l);
    if (!map->phi.empty())
    {
      return SliceValues{ map->phi.data(), 0.0f };
    }
    float cap = 0.0f;
    for (std::size_t t : { s - 1, s + 1 })
    {
      if (t < slices) // s - 1 wraps around for s = 0
      {
        const detail::SliceLabelMap * neighbour = sliceMap(t, l);
        cap = std::max(cap, neighbour->phi.empty() ? 0.0f : (map->present ? neighbour->farthest : neighbour->deepest));
      }
    }
    cap = cap > 0.0f ? cap : far;
    return SliceValues{ nullptr, map->present ? -cap : cap };
  };

  const std::size_t                m = g.factor;
  auto                             out = TLabelImage::New();
  typename TLabelImage::RegionType fine;
  typename TLabelImage::SizeType   size = region.GetSize();
  size[a] = (slices - 1) * m + 1;
  fine.SetSize(size);
  out->SetRegions(fine);
  typename TLabelImage::PointType origin;
  labels->TransformIndexToPhysicalPoint(region.GetIndex(), origin);
  out->SetOrigin(origin);
  auto spacing = labels->GetSpacing();
  spacing[a] /= double(m);
  out->SetSpacing(spacing);
  out->SetDirection(labels->GetDirection());
  out->Allocate();
  PixelType *       target = out->GetBufferPointer();
  const std::size_t outStride[3] = { 1, size[0], size[0] * size[1] };
  const auto        outOffset = [&](std::size_t p, std::size_t k) {
    return (p % n[b]) * outStride[b] + (p / n[b]) * outStride[c] + k * outStride[a];
  };
  for (std::size_t s = 0; s < slices; ++s)
  {
    for (std::size_t p = 0; p < pixels; ++p)
    {
      target[outOffset(p, s * m)] = in[offset(p, s)]; // the input's slices stay as they are
    }
    if (s + 1 == slices)
    {
      break;
    }
    for (auto it = cache.begin(); it != cache.end();)
    {
      it = it->first.first + 1 < s ? cache.erase(it) : std::next(it); // slices below s - 1 are done with
    }
    std::set<PixelType> candidates = present[s];
    candidates.insert(present[s + 1].begin(), present[s + 1].end());
    std::vector<std::pair<PixelType, std::array<SliceValues, 2>>> ends;
    for (PixelType l : candidates)
    {
      ends.push_back({ l, { { values(s, l), values(s + 1, l) } } });
    }
    for (std::size_t j = 1; j < m; ++j)
    {
      const float t = float(j) / float(m);
      for (std::size_t p = 0; p < pixels; ++p)
      {
        float     best = NumericTraits<float>::max();
        PixelType label = in[offset(p, s)];
        for (const auto & [l, end] : ends)
        {
          const float phi0 = end[0].phi ? end[0].phi[p] : end[0].constant;
          const float phi1 = end[1].phi ? end[1].phi[p] : end[1].constant;
          const float phi = (1.0f - t) * phi0 + t * phi1;
          if (phi < best)
          {
            best = phi;
            label = l;
          }
        }
        target[outOffset(p, s * m + j)] = label;
      }
    }
  }
  return out.GetPointer();
}

} // namespace itk

#endif
