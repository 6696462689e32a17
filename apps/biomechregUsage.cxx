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
// The usage text of biomechreg and of each subcommand (biomechreg help, biomechreg SUB --help).
#include "biomechregCommon.h"

#include <utility>

namespace bmrcli {
namespace {

// Options every subcommand takes (main() reads them before the subcommand's own).
const char * const globalOptions =
  "  global options: [--threads N (library and ITK threads; default: all cores)] [--quiet (warnings and errors only)]\n"
  "                  [--verbose (also every inner solve of the estimation)] [-h|--help] [--version]\n"
  "                  [--task-trace FILE (CSV of the parallel work, for benchmarks/replay_task_trace.py)]\n";

const std::pair<const char *, const char *> commands[] = {
  { "phantom",
    "  biomechreg phantom --out DIR [--scene pelvis|spheres] [--size NX,NY,NZ] [--spacing SX,SY,SZ mm]\n"
    "                     [--origin X,Y,Z mm] [--rotate-z-deg A] [--true-E-kPa E] [--true-nu NU] [--bladder-mm D]\n"
    "                     [--rectum-mm D] [--wall-load normal|point] [--truth-mesh-scale F] [--fractions off|on]\n"
    "                     [--outline-fractions off|on]\n"
    "                     [--model linear|neo_hookean] [--tissue-E-kPa E (truth's soft tissue; scene assumes 10)]\n"
    "                     [--bladder-kPa P --rectum-kPa P (pressure loads instead)]\n"
    "                     [--tumour-fraction F --tumour-E-kPa E] [--noise-HU S] [--seed N]\n"
    "                     [--tracking-noise-mm S (landmarks_tracked.csv: the fixed seeds + N(0, S^2); 0.5)]\n"
    "                     [--fixed-grid-shift-voxels S (fixed grid offset U(-S, S) voxels; default 0)]\n"
    "                     [--truth-geometry anatomy|voxels (the truth meshes the analytic anatomy the labels\n"
    "                      sample, whose surfaces stay put when --truth-mesh-scale refines; or the label map's "
    "voxels)]\n"
    "                     [--truth-refine-size-mm S [--truth-refine-distance-mm D (6)] (the truth's cells <= S mm\n"
    "                      within D mm of the prostate; pelvis 1.25 (the converged truth), spheres 0 = none)]\n"
    "    synthetic moving/fixed pair with ground truth (truth.json, truth_field.nrrd, seed landmarks)\n" },
  { "simulate",
    "  biomechreg simulate --moving-labels FILE --scene FILE --out DIR [--moving-ct FILE] [--reference IMAGE]\n"
    "    forward simulation of a scene on a moving label map: fields [mm], warped images\n" },
  { "register",
    "  biomechreg register --moving-ct FILE --moving-labels FILE --fixed-ct FILE --fixed-labels FILE\n"
    "                      [--scene FILE (without: RTSTRUCTs or named label maps, the built-in pelvis scene)]\n"
    "                      [--moving-label-names FILE --fixed-label-names FILE (value,name tables; a Slicer\n"
    "                      .seg.nrrd names its own)]\n"
    "                      [--roi-map ROI=PART,... (PART prostate|bladder|rectum|body|bone|ignore; TG-263 names\n"
    "                      are mapped by themselves)] --out DIR [--sweep-samples N] [--coarse-factor F]\n"
    "                      [--mesh-scale F] [--wall-spacing-mm D] [--wall-regularization A]\n"
    "                      [--wall-motion normal|free|traction|pressure] [--max-outer-iterations N]\n"
    "                      [--wall-basis FILE (a trained basis of wall motion, train-basis) [--basis-modes K]\n"
    "                      [--basis-prior-weight W (mm^2, 0.25)]]\n"
    "                      [--outer-tolerance T] [--element-inversion allow|limit]\n"
    "                      [--slice-interpolation off|on (organs interpolated between thick slices)]\n"
    "                      [--label-surfaces voxels|distance (the moving mesh's surfaces; default: the scene's)]\n"
    "                      [--uncertainty rescan|bootstrap|curvature|none] [--resamples N] [--uncertainty-seed S]\n"
    "                      [--uncertainty-threads T]\n"
    "                      [--uncertainty-options NAME=VALUE,... (advanced, for studies of the interval: mesh-jitter,\n"
    "                      shift-voxels, rotation-deg, wall-slip, smoothing-voxels, simulation-mesh-scale,\n"
    "                      bias-correction, warm-start, step-tolerance, quantiles, voxel-limit-mm; docs/cli.md)]\n"
    "                      [--fixed-probabilities ORGAN=FILE,...] [--unmapped-rois refuse|ignore]\n"
    "                      [--rtstruct-surfaces outlines|voxels (an RTSTRUCT's fixed organs: polygons or voxels)]\n"
    "                      [--outputs LIST|all|default (field,warped_ct,warped_labels,report; also\n"
    "                      forward_field,mesh,history,sweep,field_npz (Learn2Reg voxels))]\n"
    "                      [--field-precision float|double] [--compression-level 0-9 (labels 1, others 0)]\n"
    "    joint estimation of the wall loads and the unknown Young's moduli [kPa], with their interval;\n"
    "    writes field.nrrd (fixed -> moving, mm), warped images, report.json\n" },
  { "train-basis",
    "  biomechreg train-basis (--moving-labels FILE --fixed-labels FILE,FILE,... | --patients CSV (lines\n"
    "                         \"moving labels,fixed labels\", grouped into patients by their moving labels))\n"
    "                         --scene FILE --out BASIS.json [--modes K (all)] [--mesh-scale F]\n"
    "                         [--slice-interpolation off|on]\n"
    "    a basis of wall motion from daily scans: the moving walls matched to each fixed scan's organs (other\n"
    "    patients' walls through the first one's, fitted to theirs), their PCA (mean, modes, variances [mm^2]);\n"
    "    register --wall-basis BASIS.json moves the walls in it\n" },
  { "warp",
    "  biomechreg warp --image FILE --field FILE --out DIR [--labels off|on (on: a label map, nearest neighbour)]\n"
    "                  [--outside V (-1000, labels 0)]\n"
    "    the image resampled through a fixed -> moving field [mm] onto the field's grid: DIR/warped.nrrd; the\n"
    "    field an image or a DICOM Deformable Spatial Registration (REG, e.g. from rt-export or SlicerRT)\n" },
  { "demons",
    "  biomechreg demons --moving-ct FILE --fixed-ct FILE --out DIR [--moving-labels FILE --fixed-labels FILE\n"
    "                    --flatten LABELS] [--demons-variant diffeomorphic|symmetric] [--demons-levels N]\n"
    "                    [--demons-iterations N (per level)] [--demons-sigma S (voxels)] [--histogram-matching "
    "on|off]\n"
    "    the intensity-based baseline (ITK Demons, multi-resolution)\n" },
  { "phantom-set",
    "  biomechreg phantom-set --out DIR [--count N] [--seed S] [--prostate-E-range LO,HI (kPa; 50,300)]\n"
    "                         [--bladder-range LO,HI (mm; 3,8)] [--rectum-range LO,HI (mm; 2,5)]\n"
    "    N reproducible pelvis phantom pairs with seed landmarks and pairs.csv for compare; moduli log-uniform and\n"
    "    fillings uniform over their ranges\n" },
  { "compare",
    "  biomechreg compare --pairs LIST.csv --out DIR [--methods identity,fem,demons] [--tag T] [--seed-organ NAME]\n"
    "                     [--flatten LABELS] [register's and demons' settings]\n"
    "    FEM vs Demons vs identity on seed landmarks, with paired t-tests\n" },
  { "phantom-cohort",
    "  biomechreg phantom-cohort --out DIR [--patients N (10)] [--fractions M (6)] [--seed S] [--size NX,NY,NZ]\n"
    "                            [--spacing SX,SY,SZ mm] [--noise-HU S] [--truth-mesh-scale F]\n"
    "                            [--fixed-grid-shift-voxels S (0.5)] [--model linear|neo_hookean]\n"
    "    N pelvis phantom patients (own anatomy, T-stage, stage-linked prostate modulus) x M fractions:\n"
    "    cohort.csv for biomechreg cohort, truth.csv, truth_fractions.csv, truth_correlations.csv\n" },
  { "cohort",
    "  biomechreg cohort --cohort FILE.csv --out DIR [--cores N (all)] [--threads-per-job T (1)]\n"
    "                    [--mem-mb M (2000) --runtime-min T (30): per job, for a cluster profile]\n"
    "                    [--profile DIR (a Snakemake profile, e.g. workflows/cohort/profiles/slurm)]\n"
    "                    [--register-options \"OPTIONS\" (for every register; default --outputs report)]\n"
    "                    [--dry-run off|on]\n"
    "    the cohort workflow on Snakemake: one registration per daily image (results/, logs/), then the\n"
    "    statistics (cohort_report.md, cohort_*.csv, cohort_*.png); a re-run does only missing or failed jobs\n" },
  { "cohort-stats",
    "  biomechreg cohort-stats --cohort FILE.csv --study DIR\n"
    "    per-patient moduli and their correlation with the covariates from DIR/results (the workflow's last step)\n" },
  { "markers",
    "  biomechreg markers --planning-ct FILE --planning-labels FILE --scene FILE --planning-markers FILE\n"
    "                     --treatment-markers FILE --out DIR [--treatment-labels FILE (evaluation: IoU, D)]\n"
    "                     [--organ NAME (prostate)] [--box-margin-mm M (25)] [--control-spacing-mm S (8)]\n"
    "                     [--regularization A (1e-3)] [--mesh-scale F (1)] [--modulus NAME=E_kPa,...]\n"
    "                     [--leave-one-out on|off] [--unmapped-rois refuse|ignore]\n"
    "                     [--true-treatment-markers FILE (evaluation, phantoms: leave-one-out against the\n"
    "                      noise-free positions)]\n"
    "    the treatment anatomy from tracked markers (LPS mm; .csv, .fcsv, .json; paired by id): FEM with forces on\n"
    "    the organ's surface in a static box, against rigid alignment and a thin-plate spline; leave-one-out TRE;\n"
    "    writes field.nrrd (treatment -> planning, mm), warped_ct.nrrd, warped_labels.nrrd, report.json and the\n"
    "    references' warped_labels_rigid.nrrd, warped_labels_tps.nrrd\n" },
  { "dose",
    "  biomechreg dose --labels FILE --scene FILE --out DIR\n"
    "                  (--dose FILE (RTDOSE, or an image in Gy) | --plan-margin MM (a synthetic plan))\n"
    "                  [--field FILE (warp the dose first: out(x) = dose(x + d(x)), linear)]\n"
    "                  [--prescription-Gy RX (78)] [--penumbra-mm W (6, 80-20 %)] [--bath-fraction F (0)]\n"
    "                  [--eud-a ORGAN=A,... (defaults: prostate -10, rectum and its wall 8, bladder 2, others 1)]\n"
    "                  [--v-doses GY,... (50,60,65,70,75)] [--bin-width-Gy W (0.1)] [--prostate NAME (prostate)]\n"
    "                  [--rectum NAME (rectum)] [--plot on|off]\n"
    "    per organ and for the anterior rectal wall (rectum shell of 3 mm within 15 mm of the prostate): the\n"
    "    cumulative and differential DVH (dvh.csv, dvh.png), gEUD, Dmean, D95, D2, D98, V-doses\n"
    "    (dose_metrics.csv) and the dose on the label grid (dose.nrrd); --plan-margin makes a conformal plan\n"
    "    (PTV = prostate + margin, Rx with an erfc penumbra) instead of reading a dose\n" },
  { "rt-export",
    "  biomechreg rt-export --reference-ct DIR (the DICOM CT series the outputs belong to)\n"
    "                       [--labels FILE --scene FILE --rtstruct-out FILE.dcm (labels on that CT's grid)]\n"
    "                       [--dose FILE (RTDOSE or an image in Gy) --rtdose-out FILE.dcm [--plan-uid UID]]\n"
    "                       [--field FILE (register's field.nrrd) --moving-ct DIR --registration-out FILE.dcm]\n"
    "    a label map as a DICOM RTSTRUCT (one ROI per scene label, named as in the scene; closed planar contours\n"
    "    per slice) and a dose as an RTDOSE [Gy], with the CT's patient, study and frame of reference, e.g. the\n"
    "    warped labels and the warped dose of a registration back to a planning system; the fixed -> moving field\n"
    "    as a DICOM Deformable Spatial Registration from the reference (fixed) CT's frame to the moving CT's\n" },
};

const char * const footer =
  "Images: NRRD, NIfTI, MetaImage, ... or a DICOM series directory. Units: mm (LPS), kPa, mN, Gy.\n"
  "Label inputs of register, compare and markers may be a DICOM RTSTRUCT (ROI names = scene label names),\n"
  "gridded on the CT of the same scan; a dose may be a DICOM RTDOSE.\n"
  "Exit status: 0 success, 1 error (bad input, failed computation), 2 usage error.\n";

} // namespace

bool
IsCommand(const std::string & command)
{
  for (const auto & c : commands)
  {
    if (command == c.first)
    {
      return true;
    }
  }
  return false;
}

void
PrintUsage(std::ostream & os, const std::string & command)
{
  os << "usage:\n";
  if (command.empty())
  {
    os << "  biomechreg                      run the demo into ./biomechreg-demo\n";
  }
  for (const auto & c : commands)
  {
    if (command.empty() || command == c.first)
    {
      os << c.second;
    }
  }
  os << globalOptions << footer;
}

} // namespace bmrcli
