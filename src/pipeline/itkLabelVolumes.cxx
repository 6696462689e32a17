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
// What the scans show of the organs' filling: each label's volume in both scans.
#include "itkPipelineStages.h"

#include <limits>
#include <map>

namespace itk {
namespace {
/** The volume [mL] of each label value of \a labels. */
std::map<std::int32_t, double>
LabelVolumesML(const BiomechanicalLabelImageType * labels)
{
  std::map<std::int32_t, std::size_t> voxels;
  const auto *                        values = labels->GetBufferPointer();
  for (std::size_t i = 0, n = labels->GetBufferedRegion().GetNumberOfPixels(); i < n; ++i)
  {
    ++voxels[values[i]];
  }
  const auto &                   spacing = labels->GetSpacing();
  std::map<std::int32_t, double> volumes;
  for (const auto & [value, count] : voxels)
  {
    volumes[value] = double(count) * spacing[0] * spacing[1] * spacing[2] / 1000.0;
  }
  return volumes;
}
} // namespace

namespace pipeline {
void
MeasureLabelVolumes(RegistrationResult &                r,
                    const bmr::Scene &                  scene,
                    const BiomechanicalLabelImageType * movingLabels,
                    const BiomechanicalLabelImageType * fixedLabels)
{
  const auto moving = LabelVolumesML(movingLabels);
  const auto fixed = LabelVolumesML(fixedLabels);
  for (const auto & l : scene.labels)
  {
    if (l.role != bmr::LabelRoleEnum::Outside)
    {
      const auto m = moving.find(l.value), f = fixed.find(l.value);
      r.labelVolumeML[l.name] = { { m == moving.end() ? 0.0 : m->second, f == fixed.end() ? 0.0 : f->second } };
    }
  }
}

} // namespace pipeline

double
RegistrationResult::VolumeChangeML(const std::string & name) const
{
  const auto found = labelVolumeML.find(name);
  if (found == labelVolumeML.end() || (found->second[0] == 0.0 && found->second[1] == 0.0))
  {
    return std::numeric_limits<double>::quiet_NaN();
  }
  return found->second[1] - found->second[0];
}
} // namespace itk
