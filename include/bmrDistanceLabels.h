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
#ifndef bmrDistanceLabels_h
#define bmrDistanceLabels_h

#include "BiomechanicalRegistrationExport.h"
#include "bmrGridGeometry.h"

#include <cstdint>
#include <functional>
#include <vector>

namespace bmr {

/** \brief The labels of a label image as a function of position whose interfaces run between the slices'
 * contours instead of along the voxels' faces.
 *
 * For every label l present, the symmetric signed distance \f$ \phi_l = (\phi_{mask} - \phi_{complement}) / 2 \f$
 * [mm, negative inside] of its voxels (itk::detail::MaskAndComplementMap, the fixed organs' maps), on the box of
 * its voxels grown by two of the coarsest voxel side. A point x
 * takes the label of the smallest trilinearly interpolated \f$ \phi_l(x) \f$ among the labels at the eight voxel
 * centres around it, so every voxel centre keeps its own label and, between two slices 3 mm apart, an organ's
 * outline moves linearly from one slice's contour to the next (a ruled surface) instead of in a 1.5 mm terrace.
 * An organ ends half a slice beyond its last section at its centre, as the staircase does.
 * \a labels holds grid.GetNumberOfVoxels() values, index 0 fastest. Meshed by MeshImplicitLabelsOnGrid() where
 * MeshingParameters::labelSurfaces asks for it.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationMesh */
BiomechanicalRegistration_EXPORT std::function<std::int32_t(double, double, double)>
DistanceLabelFunction(const std::vector<std::int32_t> & labels, const GridGeometry & grid);

} // namespace bmr

#endif
