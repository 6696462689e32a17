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
// Marker-driven deformation on the pelvis phantom (2 mm voxels) with a known motion: the planning anatomy and
// its three markers translated by whole voxels, (2, -2, 2) mm, give exact treatment labels.
// - rigid alignment and the thin-plate spline reproduce a translation exactly, also leaving a marker out
//   (1e-9 mm), and the rigid warp reproduces the treatment prostate (IoU >= 0.999: exact up to ties of nearest
//   neighbour);
// - the FEM (forces on the prostate surface in a static box) fits the markers (< 0.05 mm: the prior
//   alpha = 1e-3 in mm-scaled parameters shrinks a 3.5 mm fit by about alpha) and predicts the left-out
//   marker within 0.35 mm (10 % of the motion; the prostate, 6x stiffer than the tissue, moves almost
//   rigidly while the box holds the tissue around it); its prostate overlaps the truth better than the
//   unmoved planning prostate;
// - bad input (unpaired ids, a marker in bone) is named.
#include "itkMarkerPipeline.h"

#include "bmrMarkerAlignment.h"
#include "bmrPhantom.h"
#include "bmrTestUtilities.h"
#include "itkGridGeometryConversion.h"

#include <cmath>
#include <cstdlib>

namespace {
using bmr::test::Expect;
using bmr::test::ToString;
using LabelImage = itk::BiomechanicalLabelImageType;

const int Shift[3] = { 1, -1, 1 }; // voxels of 2 mm

LabelImage::Pointer
Translated(const LabelImage * labels)
{
  auto out = LabelImage::New();
  out->CopyInformation(labels);
  out->SetRegions(labels->GetLargestPossibleRegion());
  out->Allocate();
  out->FillBuffer(bmr::PelvisAir);
  const auto region = labels->GetLargestPossibleRegion();
  for (itk::ImageRegionConstIteratorWithIndex<LabelImage> it(labels, region); !it.IsAtEnd(); ++it)
  {
    auto to = it.GetIndex();
    for (int d = 0; d < 3; ++d)
    {
      to[d] += Shift[d];
    }
    if (region.IsInside(to))
    {
      out->SetPixel(to, it.Get());
    }
  }
  return out;
}

bmr::Point3
ProstateCentroid(const LabelImage * labels)
{
  bmr::Point3 c{ { 0, 0, 0 } };
  double      n = 0;
  for (itk::ImageRegionConstIteratorWithIndex<LabelImage> it(labels, labels->GetBufferedRegion()); !it.IsAtEnd(); ++it)
  {
    if (it.Get() == bmr::PelvisProstate)
    {
      itk::Point<double, 3> x;
      labels->TransformIndexToPhysicalPoint(it.GetIndex(), x);
      for (int d = 0; d < 3; ++d)
      {
        c[d] += x[d];
      }
      ++n;
    }
  }
  for (int d = 0; d < 3; ++d)
  {
    c[d] /= n;
  }
  return c;
}

const itk::MarkerMethodResult &
Method(const itk::MarkerResult & r, const std::string & name)
{
  for (const auto & m : r.methods)
  {
    if (m.method == name)
    {
      return m;
    }
  }
  throw std::runtime_error("no method " + name);
}

double
Largest(const std::vector<double> & v)
{
  double m = 0.0;
  for (double x : v)
  {
    m = std::max(m, x);
  }
  return m;
}
} // namespace

int
itkMarkerPipelineTest(int, char *[])
{
  bmr::PelvisPhantomParameters p;
  p.grid.size = { { 100, 80, 80 } };
  p.grid.spacing = { { 2.0, 2.0, 2.0 } };
  const bmr::PhantomVolume   volume = bmr::MakePelvisPhantom(p);
  const auto                 planning = itk::MakeImageOnGrid<LabelImage>(volume.grid, volume.labels);
  const auto                 treatment = Translated(planning);
  const bmr::Point3          c = ProstateCentroid(planning);
  const double               offsets[3][3] = { { 6, 2, -4 }, { -5, 4, 3 }, { 1, -6, 5 } };
  std::vector<bmr::Landmark> from, to;
  for (int k = 0; k < 3; ++k)
  {
    bmr::Landmark m{ "gold" + std::to_string(k + 1),
                     { { c[0] + offsets[k][0], c[1] + offsets[k][1], c[2] + offsets[k][2] } } };
    from.push_back(m);
    for (int d = 0; d < 3; ++d)
    {
      m.point[d] += 2.0 * Shift[d];
    }
    to.push_back(m);
  }
  const bmr::Scene  scene = bmr::PelvisPhantomScene(60.0, false);
  itk::MarkerResult r = itk::EstimateTreatmentFromMarkers(planning, nullptr, scene, from, to);
  itk::EvaluateMarkerMethods(r, treatment, bmr::PelvisProstate);
  std::cout << r.state.mesh.GetNumberOfTetrahedra() << " tetrahedra, " << r.loadParameters << " load parameters, "
            << r.iterations << " iterations" << std::endl;
  for (const auto & m : r.methods)
  {
    std::cout << m.method << ": fit max " << Largest(m.fitResidual) << " mm, leave-one-out RMS " << m.leaveOneOutRms
              << " mm, IoU " << m.intersectionOverUnion << ", D " << m.meanSurfaceDistance << " mm" << std::endl;
  }
  const auto & fem = Method(r, "fem");
  const auto & rigid = Method(r, "rigid");
  const auto & tps = Method(r, "tps");
  const auto & none = Method(r, "none");
  bool         ok = Expect(rigid.leaveOneOutRms < 1e-9 && Largest(rigid.fitResidual) < 1e-9,
                   "rigid alignment reproduces a translation (LOO RMS " + ToString(rigid.leaveOneOutRms) + " mm)");
  ok &= Expect(tps.leaveOneOutRms < 1e-9 && Largest(tps.fitResidual) < 1e-9,
               "the spline reproduces a translation (LOO RMS " + ToString(tps.leaveOneOutRms) + " mm)");
  ok &= Expect(rigid.intersectionOverUnion >= 0.999,
               "the rigid warp reproduces the translated prostate (IoU " + ToString(rigid.intersectionOverUnion) + ")");
  ok &=
    Expect(Largest(fem.fitResidual) < 0.05, "FEM fits the markers (max " + ToString(Largest(fem.fitResidual)) + " mm)");
  ok &=
    Expect(fem.leaveOneOutRms < 0.35, "FEM predicts the left-out marker (RMS " + ToString(fem.leaveOneOutRms) + " mm)");
  ok &= Expect(fem.intersectionOverUnion > none.intersectionOverUnion + 0.1,
               "FEM moves the prostate towards the truth (IoU " + ToString(fem.intersectionOverUnion) + " against " +
                 ToString(none.intersectionOverUnion) + " unmoved)");
  // Pull-back at the prostate centroid: -shift within 10 %.
  const auto            field = fem.field;
  itk::Point<double, 3> x;
  for (int d = 0; d < 3; ++d)
  {
    x[d] = c[d] + 2.0 * Shift[d];
  }
  itk::Index<3> v;
  field->TransformPhysicalPointToIndex(x, v);
  const auto d = field->GetPixel(v);
  double     error = 0.0;
  for (int k = 0; k < 3; ++k)
  {
    error += (d[k] + 2.0 * Shift[k]) * (d[k] + 2.0 * Shift[k]);
  }
  ok &= Expect(std::sqrt(error) < 0.1 * std::sqrt(12.0),
               "FEM field at the prostate centre is the translation within 10 % (error " + ToString(std::sqrt(error)) +
                 " mm)");
  ok &= Expect(r.warnings.size() == 0, "no warning with every modulus known");

  // Leave-one-out against the true positions: the tracked ones as the truth give the tracked errors exactly; a
  // truth 0.5 mm off the tracked position of gold2 (3-4-5) gives rigid alignment and the spline, which predict the
  // tracked translation exactly, 0.5 mm there and 0 elsewhere.
  itk::EvaluateLeaveOneOutAgainstTruth(r, to);
  ok &= Expect(fem.leaveOneOutTrueError == fem.leaveOneOutError && fem.leaveOneOutTrueRms == fem.leaveOneOutRms,
               "the tracked markers as the truth give the tracked leave-one-out errors");
  auto truth = to;
  truth[1].point[0] += 0.3;
  truth[1].point[1] -= 0.4;
  itk::EvaluateLeaveOneOutAgainstTruth(r, truth);
  for (const auto * m : { &rigid, &tps })
  {
    ok &= Expect(m->leaveOneOutTrueError.size() == 3 && std::abs(m->leaveOneOutTrueError[1] - 0.5) < 1e-9 &&
                   m->leaveOneOutTrueError[0] < 1e-9 && m->leaveOneOutTrueError[2] < 1e-9,
                 m->method + ": 0.5 mm against the moved truth of gold2 only (got " +
                   ToString(m->leaveOneOutTrueError.empty() ? -1.0 : m->leaveOneOutTrueError[1]) + " mm)");
  }

  using bmr::test::ExpectException;
  auto renamed = to;
  renamed[1].id = "other";
  ok &= ExpectException(
    "unpaired id", [&] { itk::EstimateTreatmentFromMarkers(planning, nullptr, scene, from, renamed); }, "gold2");
  truth.pop_back();
  ok &= ExpectException(
    "a marker without its true position", [&] { itk::EvaluateLeaveOneOutAgainstTruth(r, truth); }, "gold3");
  auto inBone = from;
  inBone[0].point = { { c[0], c[1], c[2] - 200.0 } };
  ok &= ExpectException(
    "marker outside the box",
    [&] { itk::EstimateTreatmentFromMarkers(planning, nullptr, scene, inBone, to); },
    "gold1");
  std::cout << (ok ? "itkMarkerPipelineTest passed" : "itkMarkerPipelineTest FAILED") << std::endl;
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}
