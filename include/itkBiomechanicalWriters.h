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
#ifndef itkBiomechanicalWriters_h
#define itkBiomechanicalWriters_h

#include "itkBiomechanicalPipelines.h"

namespace itk {

/** Creates \a path and its missing parents (like mkdir -p); throws naming it when it cannot.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationIO */
BiomechanicalRegistration_EXPORT void
MakeOutputDirectory(const std::string & path);

/** mesh.vtu of a simulated or estimated state: displacement [mm], force [mN], Dirichlet flags per node;
 * label, E [kPa], nu, von Mises stress [kPa] per element (ParaView). \ingroup BiomechanicalRegistration
 * BiomechanicalRegistrationIO */
BiomechanicalRegistration_EXPORT void
WriteSimulationMesh(const std::string & path, const SimulationResult & result);

/** Writes into \a directory (created when missing): mesh.vtu, field.nrrd (fixed -> moving [mm]),
 * forward_field.nrrd (when computed), warped_labels.nrrd and warped_ct.nrrd (when given); every file through
 * a temporary name. \ingroup BiomechanicalRegistration BiomechanicalRegistrationIO */
BiomechanicalRegistration_EXPORT void
WriteSimulationOutputs(const std::string &                 directory,
                       const SimulationResult &            result,
                       const BiomechanicalLabelImageType * warpedLabels,
                       const BiomechanicalCTImageType *    warpedCT);

/** Which files WriteRegistrationOutputs() writes, and how. The defaults are what most runs use: the field, the
 * warped images and the report; the rest on request. \ingroup BiomechanicalRegistration BiomechanicalRegistrationIO */
struct BiomechanicalRegistration_EXPORT RegistrationOutputs
{
  bool field{ true };         ///< field.nrrd: fixed -> moving [mm] on the fixed grid
  bool forwardField{ false }; ///< forward_field.nrrd: moving -> fixed [mm] (needs RegistrationSettings::pushField)
  bool warpedCT{ true };      ///< warped_ct.nrrd [HU]
  bool warpedLabels{ true };  ///< warped_labels.nrrd
  bool mesh{ false };         ///< mesh.vtu: the estimated state (WriteSimulationMesh())
  bool history{ false };      ///< history.csv: every fine-mesh inner solve, then the accepted outer iterates
  bool sweep{ false };        ///< sweep.csv: Phi*(E) of the sweep
  bool report{ true };        ///< report.json: moduli, intervals, distances, Dice, wall times
  bool fieldNpz{ false };     ///< field.npz: the field in voxels, Learn2Reg's layout (WriteLearn2RegDisplacement())
  bool doubleFields{ false }; ///< the fields as double vectors; float (default) is exact to 1e-7 relative
  /** gzip level of the NRRD images: 0 none, 1 fastest ... 9 smallest; -1 (default): label maps at 1, fields and
   * CT uncompressed (DefaultCompressionLevel). */
  int compressionLevel{ -1 };

  /** Every file (the forward field too). */
  static RegistrationOutputs
  All();
  /** From a comma-separated list of field, forward_field, warped_ct, warped_labels, mesh, history, sweep,
   * report, field_npz, "all" and "default" (the sets, alone or with more items: "default,history"); throws naming the
   * unknown item. */
  static RegistrationOutputs
  Parse(const std::string & list);
};

/** Writes a registration into \a directory: the files \a outputs asks for, report.json's wall times being
 * \a stages and the writing itself; every file through a temporary name. Returns the writing's stage ("write
 * outputs").
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationIO */
BiomechanicalRegistration_EXPORT PipelineStage
WriteRegistrationOutputs(const std::string &                directory,
                         const RegistrationResult &         result,
                         const RegistrationSettings &       settings,
                         const std::vector<PipelineStage> & stages,
                         const RegistrationOutputs &        outputs = RegistrationOutputs());

/** \brief Writes a fixed -> moving field as a NumPy .npz in Learn2Reg's layout: displacements in voxels.
 *
 * The archive holds \c disp, float32 of shape (3, nx, ny, nz) (component first, then the fixed grid's index
 * i, j, k as NIfTI and nibabel order them; stored in Fortran order, i.e. ITK's own memory order), with
 * \f[ \mathrm{disp}[:, i, j, k] = \mathcal{I}_m\big(x_{ijk} + u(x_{ijk})\big) - (i, j, k), \f]
 * where \f$x_{ijk}\f$ is the fixed voxel's centre (LPS mm), \f$u\f$ the field [mm] and \f$\mathcal{I}_m\f$ the
 * continuous index of a point in \a movingGrid: the moving image is warped onto the fixed grid by sampling it at
 * (i, j, k) + disp (scipy.ndimage.map_coordinates). Learn2Reg's fixed and moving images share one grid; two
 * scans seldom do, so the moving grid is the one that counts. Beside it, in float64: \c fixed_origin,
 * \c fixed_spacing (x, y, z; mm), \c fixed_direction (3 x 3, row-major: column c is axis c's direction, LPS)
 * and the same three for the moving grid. Uncompressed (np.load maps nothing, it reads), written through a
 * temporary file; throws naming \a path when the field holds a non-finite vector or the archive would pass
 * 4 GiB (a field of about 357 million voxels). \ingroup BiomechanicalRegistration BiomechanicalRegistrationIO */
BiomechanicalRegistration_EXPORT void
WriteLearn2RegDisplacement(const BiomechanicalFieldType * field,
                           const ImageBase<3> *           movingGrid,
                           const std::string &            path);

/** Writes a phantom pair into \a directory: moving and fixed CT and labels, truth_field.nrrd, scene.json (what
 * the estimator sees), truth_scene.json, truth.json and the seed landmarks. \ingroup BiomechanicalRegistration
 * BiomechanicalRegistrationIO */
BiomechanicalRegistration_EXPORT void
WritePhantomPair(const std::string & directory, const PhantomPair & pair, const PhantomSettings & settings);

} // namespace itk

#endif
