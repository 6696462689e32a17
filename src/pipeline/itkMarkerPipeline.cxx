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
// Marker-driven deformation (dissertation chapter 4): static box, surface forces, landmark term; rigid and
// thin-plate-spline references; leave-one-out prediction.
#include "itkMarkerPipeline.h"
#include "itkPipelineStages.h"

#include "bmrError.h"
#include "bmrEstimationObjective.h"
#include "bmrLandmarkTerm.h"
#include "bmrMarkerAlignment.h"
#include "bmrOrganSurfaceForces.h"
#include "bmrSimulation.h"

#include "itkImageDuplicator.h"
#include "itkImageRegionIteratorWithIndex.h"
#include "itkRegistrationQualityMeasures.h"
#include "itkSignedMaurerDistanceMapImageFilter.h"
#include "itkRegionOfInterestImageFilter.h"

#include <cmath>
#include <functional>
#include <sstream>

namespace itk {
namespace {
using PointList = std::vector<bmr::Point3>;

/** The markers of both lists paired by id, in the planning list's order. */
void
PairMarkers(const std::vector<bmr::Landmark> & planning,
            const std::vector<bmr::Landmark> & treatment,
            std::vector<std::string> &         ids,
            PointList &                        from,
            PointList &                        to)
{
  if (planning.size() < 2)
  {
    bmr::Fail("EstimateTreatmentFromMarkers",
              "at least two planning markers are needed, got " + std::to_string(planning.size()));
  }
  if (planning.size() != treatment.size())
  {
    bmr::Fail("EstimateTreatmentFromMarkers",
              std::to_string(planning.size()) + " planning markers but " + std::to_string(treatment.size()) +
                " treatment markers");
  }
  for (const bmr::Landmark & p : planning)
  {
    auto match =
      std::find_if(treatment.begin(), treatment.end(), [&](const bmr::Landmark & t) { return t.id == p.id; });
    if (match == treatment.end())
    {
      bmr::Fail("EstimateTreatmentFromMarkers", "planning marker \"" + p.id + "\" has no treatment marker of that id");
    }
    ids.push_back(p.id);
    from.push_back(p.point);
    to.push_back(match->point);
  }
}

/** The scene of the box model: no wall loads and no objective, unknown moduli made known, the box held. */
bmr::Scene
MarkerScene(const bmr::Scene & scene, const MarkerSettings & settings, MarkerResult & result)
{
  bmr::Scene box = ScaledMeshSizes(scene, settings.meshScale);
  box.loads.clear();
  box.objective.clear();
  box.forceSurfaces.clear();
  box.roiMargin = -1.0;
  box.roiBoundaryFixed = true;
  for (auto & l : box.labels)
  {
    const auto given = settings.moduli.find(l.name);
    if (given != settings.moduli.end())
    {
      if (!(given->second > 0.0) || !std::isfinite(given->second))
      {
        bmr::Fail("EstimateTreatmentFromMarkers", "the modulus of \"" + l.name + "\" must be finite and > 0 kPa");
      }
      l.youngsModulus = given->second;
    }
    else if (l.role == bmr::LabelRoleEnum::UnknownMaterial)
    {
      std::ostringstream os;
      os << "the scene leaves the modulus of \"" << l.name << "\" unknown: the marker model assumes its initial value "
         << l.youngsModulus << " kPa (give it with --modulus " << l.name << "=E)";
      result.warnings.push_back(os.str());
    }
    if (l.role == bmr::LabelRoleEnum::UnknownMaterial)
    {
      l.role = bmr::LabelRoleEnum::Material;
    }
    if (l.role == bmr::LabelRoleEnum::Material)
    {
      result.moduli[l.name] = l.youngsModulus;
    }
  }
  for (const auto & kv : settings.moduli)
  {
    if (box.FindLabel(kv.first) == nullptr)
    {
      bmr::Fail("EstimateTreatmentFromMarkers", "--modulus names \"" + kv.first + "\", which is not a scene label");
    }
  }
  return box;
}

/** The organ's bounding box widened by \a margin [mm], clipped to the image. */
ImageRegion<3>
OrganBox(const BiomechanicalLabelImageType * labels, std::int32_t organ, double margin, MarkerResult & result)
{
  Index<3> lo, hi;
  lo.Fill(NumericTraits<IndexValueType>::max());
  hi.Fill(NumericTraits<IndexValueType>::NonpositiveMin());
  bool found = false;
  for (ImageRegionConstIteratorWithIndex<BiomechanicalLabelImageType> it(labels, labels->GetBufferedRegion());
       !it.IsAtEnd();
       ++it)
  {
    if (it.Get() == organ)
    {
      found = true;
      for (unsigned int d = 0; d < 3; ++d)
      {
        lo[d] = std::min(lo[d], it.GetIndex()[d]);
        hi[d] = std::max(hi[d], it.GetIndex()[d]);
      }
    }
  }
  if (!found)
  {
    bmr::Fail("EstimateTreatmentFromMarkers",
              "the planning labels contain no voxel of the organ (label " + std::to_string(organ) + ")");
  }
  const ImageRegion<3> whole = labels->GetBufferedRegion();
  bool                 clipped = false;
  for (unsigned int d = 0; d < 3; ++d)
  {
    const auto           m = static_cast<IndexValueType>(std::ceil(margin / labels->GetSpacing()[d]));
    const IndexValueType first = whole.GetIndex(d), last = first + static_cast<IndexValueType>(whole.GetSize(d)) - 1;
    clipped = clipped || lo[d] - m < first || hi[d] + m > last;
    lo[d] = std::max(first, lo[d] - m);
    hi[d] = std::min(last, hi[d] + m);
  }
  if (clipped)
  {
    result.warnings.push_back("the box around the organ reaches the image border: the border holds the tissue there");
  }
  ImageRegion<3> box;
  box.SetIndex(lo);
  for (unsigned int d = 0; d < 3; ++d)
  {
    box.SetSize(d, static_cast<SizeValueType>(hi[d] - lo[d] + 1));
  }
  return box;
}

BiomechanicalLabelImageType::Pointer
Crop(const BiomechanicalLabelImageType * labels, const ImageRegion<3> & box)
{
  auto roi = RegionOfInterestImageFilter<BiomechanicalLabelImageType, BiomechanicalLabelImageType>::New();
  roi->SetInput(labels);
  roi->SetRegionOfInterest(box);
  roi->Update();
  return roi->GetOutput();
}

/** kappa = 10 mu a / sqrt(|S|) (bmr::OrganSurfaceForces): a from the organ's surface area, mu of the softest
 * known material around it. */
double
ForceScale(const bmr::TetrahedralMesh & mesh, const bmr::Scene & box, std::int32_t organ, std::size_t surfaceNodes)
{
  const std::vector<std::int32_t> faces = bmr::LabelSurfaceFaces(mesh, organ);
  double                          area = 0.0;
  for (std::size_t f = 0; f + 2 < faces.size(); f += 3)
  {
    const double * x0 = &mesh.points[3 * static_cast<std::size_t>(faces[f])];
    const double * x1 = &mesh.points[3 * static_cast<std::size_t>(faces[f + 1])];
    const double * x2 = &mesh.points[3 * static_cast<std::size_t>(faces[f + 2])];
    const double   a[3] = { x1[0] - x0[0], x1[1] - x0[1], x1[2] - x0[2] };
    const double   b[3] = { x2[0] - x0[0], x2[1] - x0[1], x2[2] - x0[2] };
    area += 0.5 * std::hypot(a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]);
  }
  double shear = std::numeric_limits<double>::infinity();
  for (const auto & l : box.labels)
  {
    if (l.role == bmr::LabelRoleEnum::Material && l.value != organ)
    {
      shear = std::min(shear, l.youngsModulus / (2.0 * (1.0 + l.poissonRatio)));
    }
  }
  if (!std::isfinite(shear))
  {
    const bmr::SceneLabel * o = box.FindLabelValue(organ);
    shear = o->youngsModulus / (2.0 * (1.0 + o->poissonRatio));
  }
  const double radius = std::sqrt(area / (4.0 * itk::Math::pi));
  return 10.0 * shear * radius / std::sqrt(static_cast<double>(surfaceNodes));
}

/** The FEM model of the box and its fit to weighted markers. */
struct BoxModel
{
  const bmr::TetrahedralMesh &             mesh;
  std::unique_ptr<bmr::ForwardModel>       model;
  std::unique_ptr<bmr::OrganSurfaceForces> loads;
  const MarkerSettings &                   settings;

  /** Nodal displacement [mm] fitted to the markers with the given weights; \a iterations receives the LM's and
   * \a forces the nodal forces [mN] of the fit, when not null. */
  std::vector<double>
  Fit(const PointList &           from,
      const PointList &           to,
      const std::vector<double> & weights,
      unsigned int *              iterations,
      std::vector<double> *       forces = nullptr) const
  {
    std::vector<bmr::LandmarkTarget> targets;
    for (std::size_t k = 0; k < from.size(); ++k)
    {
      targets.push_back({ "marker " + std::to_string(k + 1), from[k], to[k], weights[k] });
    }
    const bmr::LandmarkTerm  term(mesh, targets);
    bmr::EstimationObjective objective(*model, *loads, { &term }, {});
    const bmr::LoadSolution  solution = objective.SolveLoadsLevenbergMarquardt(
      std::vector<double>(loads->GetNumberOfParameters(), 0.0), settings.maximumIterations, 1e-8);
    if (iterations)
    {
      *iterations = solution.iterations;
    }
    if (forces)
    {
      *forces = loads->Apply(solution.parameters).forces;
    }
    return objective.ComputeDisplacement(solution.parameters);
  }
};

/** Distances [mm] between predicted and tracked positions. */
std::vector<double>
Distances(const PointList & predicted, const PointList & to)
{
  std::vector<double> d;
  for (std::size_t k = 0; k < to.size(); ++k)
  {
    d.push_back(std::hypot(predicted[k][0] - to[k][0], predicted[k][1] - to[k][1], predicted[k][2] - to[k][2]));
  }
  return d;
}

double
Rms(const std::vector<double> & values)
{
  double sum = 0.0;
  for (double v : values)
  {
    sum += v * v;
  }
  return values.empty() ? -1.0 : std::sqrt(sum / static_cast<double>(values.size()));
}

/** Each marker predicted by \a predict fitted to the others. */
PointList
LeaveOneOut(const PointList &                                                                             from,
            const PointList &                                                                             to,
            const std::function<bmr::Point3(const PointList &, const PointList &, const bmr::Point3 &)> & predict)
{
  PointList predictions;
  for (std::size_t k = 0; k < from.size(); ++k)
  {
    PointList a, b;
    for (std::size_t j = 0; j < from.size(); ++j)
    {
      if (j != k)
      {
        a.push_back(from[j]);
        b.push_back(to[j]);
      }
    }
    predictions.push_back(predict(a, b, from[k]));
  }
  return predictions;
}

/** \a m's leave-one-out predictions and their errors against the tracked positions \a to. */
void
SetLeaveOneOut(MarkerMethodResult & m, const PointList & predictions, const PointList & to)
{
  m.leaveOneOutPrediction = predictions;
  m.leaveOneOutError = Distances(predictions, to);
  m.leaveOneOutRms = Rms(m.leaveOneOutError);
}

/** The pull-back field of a point map treatment -> planning on \a reference's grid. */
BiomechanicalFieldType::Pointer
FieldOfMap(const ImageBase<3> * reference, const std::function<bmr::Point3(const bmr::Point3 &)> & toPlanning)
{
  auto field = BiomechanicalFieldType::New();
  field->CopyInformation(reference);
  field->SetRegions(reference->GetLargestPossibleRegion());
  field->Allocate();
  for (ImageRegionIteratorWithIndex<BiomechanicalFieldType> it(field, field->GetBufferedRegion()); !it.IsAtEnd(); ++it)
  {
    Point<double, 3> x;
    field->TransformIndexToPhysicalPoint(it.GetIndex(), x);
    const bmr::Point3                 y = toPlanning({ { x[0], x[1], x[2] } });
    BiomechanicalFieldType::PixelType d;
    for (unsigned int c = 0; c < 3; ++c)
    {
      d[c] = y[c] - x[c];
    }
    it.Set(d);
  }
  return field;
}

/** The FEM fit to every marker (its displacement in \a u) and, when asked, to all but each one. */
MarkerMethodResult
FemMethod(const BoxModel &      box,
          const PointList &     from,
          const PointList &     to,
          bool                  leaveOneOut,
          std::vector<double> & u,
          std::vector<double> & forces,
          unsigned int &        iterations)
{
  MarkerMethodResult fem;
  fem.method = "fem";
  u = box.Fit(from, to, std::vector<double>(from.size(), 1.0), &iterations, &forces);
  std::vector<bmr::LandmarkTarget> all;
  for (std::size_t k = 0; k < from.size(); ++k)
  {
    all.push_back({ "", from[k], to[k], 1.0 });
  }
  const bmr::LandmarkTerm probe(box.mesh, all);
  fem.fitResidual = Distances(probe.DeformedPositions(u), to);
  if (leaveOneOut)
  {
    PointList predictions;
    for (std::size_t k = 0; k < from.size(); ++k)
    {
      std::vector<double> weights(from.size(), 1.0);
      weights[k] = 0.0;
      const std::vector<double> uk = box.Fit(from, to, weights, nullptr);
      predictions.push_back(probe.DeformedPositions(uk)[k]);
    }
    SetLeaveOneOut(fem, predictions, to);
  }
  return fem;
}
} // namespace

namespace {
/** Rigid motion and thin-plate spline from the markers: fields, fit residuals and leave-one-out errors. */
std::vector<MarkerMethodResult>
ReferenceMethods(const ImageBase<3> * reference, const PointList & from, const PointList & to, bool leaveOneOut)
{
  MarkerMethodResult rigid, tps;
  rigid.method = "rigid";
  tps.method = "tps";
  const bmr::RigidTransform motion = bmr::FitRigidTransform(from, to);
  // Fitted from treatment to planning, the spline is itself the pull-back (no inversion needed).
  const bmr::ThinPlateSpline back(to, from), forward(from, to);
  PointList                  viaRigid, viaSpline;
  for (std::size_t k = 0; k < from.size(); ++k)
  {
    viaRigid.push_back(motion.Apply(from[k]));
    viaSpline.push_back(forward.Apply(from[k]));
  }
  rigid.fitResidual = Distances(viaRigid, to);
  tps.fitResidual = Distances(viaSpline, to);
  if (leaveOneOut)
  {
    const auto rigidPredicts = [](const PointList & a, const PointList & b, const bmr::Point3 & x) {
      return bmr::FitRigidTransform(a, b).Apply(x);
    };
    const auto splinePredicts = [](const PointList & a, const PointList & b, const bmr::Point3 & x) {
      return bmr::ThinPlateSpline(a, b).Apply(x);
    };
    SetLeaveOneOut(rigid, LeaveOneOut(from, to, rigidPredicts), to);
    SetLeaveOneOut(tps, LeaveOneOut(from, to, splinePredicts), to);
  }
  rigid.field = FieldOfMap(reference, [&](const bmr::Point3 & y) { return motion.ApplyInverse(y); });
  tps.field = FieldOfMap(reference, [&](const bmr::Point3 & y) { return back.Apply(y); });
  return { rigid, tps };
}

/** The planning anatomy left where it was: what the markers' motion is measured against. */
MarkerMethodResult
Unmoved(const BiomechanicalLabelImageType * planningLabels,
        const PointList &                   from,
        const PointList &                   to,
        bool                                leaveOneOut)
{
  MarkerMethodResult none;
  none.method = "none";
  none.fitResidual = Distances(from, to);
  if (leaveOneOut)
  {
    SetLeaveOneOut(none, from, to); // the planning positions, whichever markers are left out
  }
  auto copy = ImageDuplicator<BiomechanicalLabelImageType>::New();
  copy->SetInputImage(planningLabels);
  copy->Update();
  none.warpedLabels = copy->GetOutput();
  return none;
}

/** Throws naming the first marker outside the meshed box. */
void
CheckMarkersInMesh(const bmr::TetrahedralMesh & mesh, const std::vector<std::string> & ids, const PointList & from)
{
  for (std::size_t k = 0; k < from.size(); ++k)
  {
    bmr::MeshLocation where;
    if (!bmr::LocateInMesh(mesh, from[k], where))
    {
      bmr::Fail("EstimateTreatmentFromMarkers",
                "planning marker \"" + ids[k] +
                  "\" lies outside the meshed box (in a lumen, bone or beyond the "
                  "box margin); widen the box margin or check the marker file");
    }
  }
}

/** The FEM model of the box in \a result's mesh: its forward model and the surface forces on \a organ, scaled and
 * regularized; their sizes go into \a result. */
BoxModel
MakeBoxModel(const bmr::Scene & boxScene, std::int32_t organ, const MarkerSettings & settings, MarkerResult & result)
{
  const bmr::BoundaryConditions bc = bmr::SceneBoundaryConditions(boxScene, result.state.mesh);
  auto     model = bmr::MakeForwardModel(boxScene, result.state.mesh, bmr::SceneMaterials(boxScene));
  BoxModel box{ result.state.mesh, std::move(model), nullptr, settings };
  box.loads = std::make_unique<bmr::OrganSurfaceForces>(result.state.mesh,
                                                        bc.dirichletNodes,
                                                        bc.dirichletValues,
                                                        bmr::NodesOnLabelSurface(result.state.mesh, organ),
                                                        settings.controlSpacing);
  result.forceScale = ForceScale(result.state.mesh, boxScene, organ, box.loads->GetSurfaceNodes().size());
  box.loads->SetForceScale(result.forceScale);
  box.loads->SetRegularization(settings.regularization);
  result.loadParameters = box.loads->GetNumberOfParameters();
  result.surfaceNodes = box.loads->GetSurfaceNodes().size();
  result.heldNodes = bc.dirichletNodes.size();
  return box;
}
} // namespace

MarkerResult
EstimateTreatmentFromMarkers(const BiomechanicalLabelImageType * planningLabels,
                             const BiomechanicalCTImageType *    planningCT,
                             const bmr::Scene &                  scene,
                             const std::vector<bmr::Landmark> &  planningMarkers,
                             const std::vector<bmr::Landmark> &  treatmentMarkers,
                             const MarkerSettings &              settings,
                             PipelineObserver *                  observer)
{
  if (planningLabels == nullptr)
  {
    bmr::Fail("EstimateTreatmentFromMarkers", "the planning label image is required");
  }
  if (!(settings.boxMargin > 0.0) || !(settings.controlSpacing > 0.0) || !(settings.meshScale > 0.0) ||
      !std::isfinite(settings.boxMargin + settings.controlSpacing + settings.meshScale))
  {
    bmr::Fail("EstimateTreatmentFromMarkers", "the box margin, control spacing and mesh scale must be finite and > 0");
  }
  MarkerResult         r;
  pipeline::StageClock clock(observer, r.stages);
  PointList            from, to;
  PairMarkers(planningMarkers, treatmentMarkers, r.markerIds, from, to);
  const bmr::SceneLabel * organ = scene.FindLabel(settings.organ);
  if (organ == nullptr ||
      (organ->role != bmr::LabelRoleEnum::Material && organ->role != bmr::LabelRoleEnum::UnknownMaterial))
  {
    bmr::Fail("EstimateTreatmentFromMarkers",
              "the organ \"" + settings.organ + "\" is not a simulated label of the scene");
  }
  const bmr::Scene boxScene = MarkerScene(scene, settings, r);
  const bool       leaveOneOut = settings.leaveOneOut && from.size() >= 3;

  const auto boxLabels = Crop(planningLabels, OrganBox(planningLabels, organ->value, settings.boxMargin, r));
  r.state.mesh = pipeline::MeshLabelImage(boxLabels, boxScene, clock, "mesh of the box (CGAL Mesh_3)");
  CheckMarkersInMesh(r.state.mesh, r.markerIds, from);

  clock.Begin("FEM fit to the markers (surface forces, Levenberg-Marquardt)");
  BoxModel            box = MakeBoxModel(boxScene, organ->value, settings, r);
  std::vector<double> u;
  r.methods.push_back(FemMethod(box, from, to, leaveOneOut, u, r.surfaceForces, r.iterations));
  r.state.mesh.displacement = u;
  std::ostringstream fit;
  fit << r.loadParameters << " load parameters, " << r.iterations << " iterations, RMS fit "
      << Rms(r.methods[0].fitResidual) << " mm";
  clock.End(fit.str());

  // The box mesh lives on the cropped grid; its field goes on the whole planning grid.
  pipeline::ComputeFields(r.state, planningLabels, planningLabels, false, boxScene, clock);
  r.methods[0].field = r.state.pullBack;
  clock.Begin("rigid and thin-plate-spline references");
  for (auto & m : ReferenceMethods(planningLabels, from, to, leaveOneOut))
  {
    r.methods.push_back(m);
  }
  clock.End();
  clock.Begin("warp (CT linear; labels nearest)");
  for (auto & m : r.methods)
  {
    m.warpedLabels = WarpImage(planningLabels, m.field.GetPointer(), true, 0);
  }
  r.methods.push_back(Unmoved(planningLabels, from, to, leaveOneOut));
  if (planningCT)
  {
    r.warpedCT = WarpImage(planningCT, r.state.pullBack.GetPointer(), false, -1000.0f);
  }
  clock.End();
  return r;
}

namespace {
/** Mean distance [mm] from the surface voxels of \a organ in \a truth to its surface in \a estimate. */
double
MeanOneSidedSurfaceDistance(const BiomechanicalLabelImageType * truth,
                            const BiomechanicalLabelImageType * estimate,
                            std::int32_t                        organ)
{
  using MaskType = Image<unsigned char, 3>;
  using MapType = Image<float, 3>;
  auto mask = MaskType::New();
  mask->CopyInformation(estimate);
  mask->SetRegions(estimate->GetBufferedRegion());
  mask->Allocate();
  ImageRegionConstIterator<BiomechanicalLabelImageType> in(estimate, estimate->GetBufferedRegion());
  for (ImageRegionIterator<MaskType> out(mask, mask->GetBufferedRegion()); !out.IsAtEnd(); ++out, ++in)
  {
    out.Set(in.Get() == organ ? 1 : 0);
  }
  auto maurer = SignedMaurerDistanceMapImageFilter<MaskType, MapType>::New();
  maurer->SetInput(mask);
  maurer->SetUseImageSpacing(true);
  maurer->SetSquaredDistance(false);
  maurer->Update();
  const MapType * distance = maurer->GetOutput();
  const auto      region = truth->GetBufferedRegion();
  double          sum = 0.0;
  std::size_t     count = 0;
  for (ImageRegionConstIteratorWithIndex<BiomechanicalLabelImageType> it(truth, region); !it.IsAtEnd(); ++it)
  {
    bool surface = false;
    for (unsigned int axis = 0; axis < 3 && it.Get() == organ && !surface; ++axis)
    {
      for (int step = -1; step <= 1 && !surface; step += 2)
      {
        auto n = it.GetIndex();
        n[axis] += step;
        surface = !region.IsInside(n) || truth->GetPixel(n) != organ;
      }
    }
    if (surface)
    {
      sum += std::abs(double(distance->GetPixel(it.GetIndex())));
      ++count;
    }
  }
  return count == 0 ? -1.0 : sum / static_cast<double>(count);
}
} // namespace

void
EvaluateMarkerMethods(MarkerResult &                      result,
                      const BiomechanicalLabelImageType * treatmentLabels,
                      std::int32_t                        organLabel)
{
  if (treatmentLabels == nullptr)
  {
    bmr::Fail("EvaluateMarkerMethods", "the treatment label image is required");
  }
  for (MarkerMethodResult & m : result.methods)
  {
    if (m.warpedLabels->GetLargestPossibleRegion() != treatmentLabels->GetLargestPossibleRegion() ||
        !m.warpedLabels->GetOrigin().GetVnlVector().is_equal(treatmentLabels->GetOrigin().GetVnlVector(), 1e-6) ||
        !m.warpedLabels->GetSpacing().GetVnlVector().is_equal(treatmentLabels->GetSpacing().GetVnlVector(), 1e-9))
    {
      bmr::Fail("EvaluateMarkerMethods", "the treatment labels must lie on the planning grid");
    }
    const LabelOverlap o = ComputeLabelOverlap(m.warpedLabels.GetPointer(), treatmentLabels, organLabel);
    if (o.inB == 0)
    {
      bmr::Fail("EvaluateMarkerMethods",
                "the treatment labels contain no voxel of label " + std::to_string(organLabel));
    }
    m.intersectionOverUnion = static_cast<double>(o.inBoth) / static_cast<double>(o.inA + o.inB - o.inBoth);
    m.meanSurfaceDistance = MeanOneSidedSurfaceDistance(treatmentLabels, m.warpedLabels.GetPointer(), organLabel);
  }
}

void
EvaluateLeaveOneOutAgainstTruth(MarkerResult & result, const std::vector<bmr::Landmark> & trueTreatmentMarkers)
{
  const bool predicted = std::any_of(result.methods.begin(), result.methods.end(), [](const MarkerMethodResult & m) {
    return !m.leaveOneOutPrediction.empty();
  });
  if (!predicted)
  {
    return; // no leave-one-out (turned off, or fewer than three markers)
  }
  PointList truth;
  for (const std::string & id : result.markerIds)
  {
    const auto found = std::find_if(
      trueTreatmentMarkers.begin(), trueTreatmentMarkers.end(), [&id](const bmr::Landmark & l) { return l.id == id; });
    if (found == trueTreatmentMarkers.end())
    {
      bmr::Fail("EvaluateLeaveOneOutAgainstTruth", "marker \"" + id + "\" has no true treatment position");
    }
    truth.push_back(found->point);
  }
  for (MarkerMethodResult & m : result.methods)
  {
    if (m.leaveOneOutPrediction.size() == truth.size())
    {
      m.leaveOneOutTrueError = Distances(m.leaveOneOutPrediction, truth);
      m.leaveOneOutTrueRms = Rms(m.leaveOneOutTrueError);
    }
  }
}

std::vector<bmr::Landmark>
AddTrackingNoise(std::vector<bmr::Landmark> markers, double sigma, std::uint64_t seed)
{
  if (!std::isfinite(sigma) || sigma < 0.0)
  {
    bmr::Fail("AddTrackingNoise", "the tracking noise must be finite and >= 0 mm");
  }
  std::mt19937_64 rng(seed * 2654435761ULL + 97);
  for (bmr::Landmark & m : markers)
  {
    for (int c = 0; c < 3; ++c)
    {
      // Box-Muller from the platform-independent uniforms of pipeline::Uniform.
      const double u1 = 1.0 - pipeline::Uniform(rng, 0.0, 1.0), u2 = pipeline::Uniform(rng, 0.0, 1.0);
      m.point[c] += sigma * std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * itk::Math::pi * u2);
    }
  }
  return markers;
}

} // namespace itk
