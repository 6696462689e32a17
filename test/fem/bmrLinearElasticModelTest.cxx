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
// Linear-elastic FEM core: patch test, scale invariance of u under E, F -> 10^k (E, F),
// reaction forces in equilibrium, reuse of the factorization, the host's BLAS threads left alone, CHOLMOD's OpenMP
// regions serialized on the solving thread (and the thread's setting restored), and every error path.
#include "bmrLinearElasticModel.h"
#include "bmrNumerics.h"
#include "bmrTestUtilities.h"

#include <dlfcn.h>

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <iterator>
#include <thread>
#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <cstdlib>

namespace {
double
RelativeDifference(const std::vector<double> & a, const std::vector<double> & b)
{
  double num = 0.0, den = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i)
  {
    num += (a[i] - b[i]) * (a[i] - b[i]);
    den += b[i] * b[i];
  }
  return std::sqrt(num / den);
}

/** Moduli changed by 0.2 % (one up, one down) are solved without refactorizing (IsFactorized() stays false), by
 * conjugate gradients preconditioned with the kept factorization: equal to a refactorized model's solution to a
 * relative 1e-10 (the iteration stops at 1e-13 of |u|; the rest is the two solves' rounding), while the change moves
 * u by far more, so the stale factorization alone would fail. A 0.7 % change, above the 0.3 % threshold, refactorizes.
 */
bool
CheckRefactorizationThreshold(const bmr::TetrahedralMesh &      mesh,
                              const std::vector<std::int32_t> & held,
                              const std::vector<double> &       forces)
{
  using bmr::test::Expect;
  using bmr::test::ToString;
  const std::map<std::int32_t, bmr::MaterialParameters> materials{ { 1, { 10.0, 0.35 } }, { 2, { 50.0, 0.4 } } };
  bmr::LinearElasticModel                               iterated(mesh, materials), direct(mesh, materials);
  iterated.SetDirichletConditions(held, {});
  direct.SetDirichletConditions(held, {});
  direct.SetRefactorizationThreshold(0.0);
  const std::vector<double> before = iterated.Solve(forces);
  for (bmr::LinearElasticModel * m : { &iterated, &direct })
  {
    m->SetYoungsModulus(1, 10.0 * 0.998);
    m->SetYoungsModulus(2, 50.0 * 1.002);
  }
  const std::vector<double> ui = iterated.Solve(forces), ud = direct.Solve(forces);
  const double              difference = RelativeDifference(ui, ud), change = RelativeDifference(before, ud);
  std::cout << "moduli changed by 0.2 %: u moves by " << change << " (relative); iterated against refactorized "
            << difference << std::endl;
  bool ok = Expect(!iterated.IsFactorized() && direct.IsFactorized(),
                   "a 0.2 % change iterates without refactorizing, threshold 0 refactorizes");
  ok &=
    Expect(difference <= 1e-10,
           "the iterated solution equals the refactorized one to a relative 1e-10 (got " + ToString(difference) + ")");
  ok &= Expect(change >= 1e-3, "the change moves u by a relative 1e-3 or more (got " + ToString(change) + ")");
  iterated.SetYoungsModulus(2, 50.0 * 1.007);
  iterated.Solve(forces);
  ok &= Expect(iterated.IsFactorized(), "a 0.7 % change (above the 0.3 % threshold) refactorizes");
  ok &= bmr::test::ExpectException(
    "refactorization threshold 1", [&] { iterated.SetRefactorizationThreshold(1.0); }, "[0, 1)");
  return ok;
}

std::size_t
NumberOfThreads()
{
  return static_cast<std::size_t>(
    std::distance(std::filesystem::directory_iterator("/proc/self/task"), std::filesystem::directory_iterator()));
}

/** CHOLMOD's OpenMP regions run on the solving thread, and the thread's own OpenMP setting is left as it was.
 * (1) Factorizing a model with supernodes large enough for CHOLMOD's parallel copy loops (a 16^3-node cube) starts
 * no thread: a team of 4 would leave libgomp's 3 idle workers behind. (2) A thread whose max active levels were 2
 * before a solve has 2 after it. Skipped when no OpenMP runtime is loaded (a CHOLMOD built without it). Run first,
 * while no other thread of the process can start or end threads. */
bool
CheckSerialOpenMP()
{
  using GetLevels = int (*)();
  using SetLevels = void (*)(int);
  const auto get = reinterpret_cast<GetLevels>(dlsym(RTLD_DEFAULT, "omp_get_max_active_levels"));
  const auto set = reinterpret_cast<SetLevels>(dlsym(RTLD_DEFAULT, "omp_set_max_active_levels"));
  if (get == nullptr || set == nullptr)
  {
    std::cout << "no OpenMP runtime loaded: nothing to serialize" << std::endl;
    return true;
  }
  const bmr::TetrahedralMesh mesh = bmr::test::StructuredCube(15, 1.0);
  std::vector<std::int32_t>  bottom;
  for (std::size_t n = 0; n < mesh.GetNumberOfPoints(); ++n)
  {
    if (mesh.points[3 * n + 2] == 0.0)
    {
      bottom.push_back(static_cast<std::int32_t>(n));
    }
  }
  std::vector<double> forces(mesh.points.size(), 0.0);
  forces.back() = 1.0;
  std::size_t started = 0;
  int         after = -1;
  std::thread([&] {
    // Counted before the thread ends: libgomp's workers live as long as the thread whose team they were.
    const std::size_t before = NumberOfThreads();
    set(2);
    bmr::LinearElasticModel model(mesh, { { 1, { 10.0, 0.3 } } });
    model.SetDirichletConditions(bottom, {});
    model.Solve(forces);
    after = get();
    started = NumberOfThreads() - before;
  }).join();
  std::cout << "threads left by a factorization: " << started << "; max active levels 2 before a solve, " << after
            << " after" << std::endl;
  return bmr::test::Expect(started == 0, "CHOLMOD's parallel regions ran on the solving thread") &&
         bmr::test::Expect(after == 2, "the thread's own OpenMP setting is restored");
}

/** |f - K u| / |f| on the free dofs of \a model. */
double
RelativeResidual(const bmr::LinearElasticModel & model,
                 const std::vector<double> &     forces,
                 const std::vector<double> &     u)
{
  const std::vector<double> Ku = model.ComputeInternalForces(u);
  const std::vector<char> & held = model.GetConstrainedDegreesOfFreedom();
  double                    residual = 0.0, load = 0.0;
  for (std::size_t i = 0; i < forces.size(); ++i)
  {
    if (!held[i])
    {
      residual += (forces[i] - Ku[i]) * (forces[i] - Ku[i]);
      load += forces[i] * forces[i];
    }
  }
  return std::sqrt(residual / load);
}

/** The nodes on the plane z = 0, held fixed in the cube tests. */
std::vector<std::int32_t>
BottomNodes(const bmr::TetrahedralMesh & mesh)
{
  std::vector<std::int32_t> bottom;
  for (std::size_t n = 0; n < mesh.GetNumberOfPoints(); ++n)
  {
    if (mesh.points[3 * n + 2] == 0.0)
    {
      bottom.push_back(static_cast<std::int32_t>(n));
    }
  }
  return bottom;
}

/** A load on every one of \a count dofs that differs from dof to dof [mN]. */
std::vector<double>
SpreadForces(std::size_t count)
{
  std::vector<double> forces(count);
  for (std::size_t i = 0; i < count; ++i)
  {
    forces[i] = std::sin(0.37 * static_cast<double>(i)) + 0.1 * static_cast<double>(i % 3);
  }
  return forces;
}

/** The library leaves the BLAS's thread count to its host (bmr::ConfigureNumerics() is the program's call, not the
 * library's): a factorization and solve made while OpenBLAS runs 2 threads leave it at 2, and give the one-thread
 * displacements to a relative 1e-12 (a partitioned BLAS only sums in another order; the factor's conditioning on a
 * 16^3-node cube keeps that rounding far below it). Run first, before any other factorization of the process.
 * Skipped without OpenBLAS. */
bool
CheckBlasLeftToHost()
{
  using bmr::test::Expect;
  if (bmr::BlasThreads() < 0)
  {
    std::cout << "the BLAS is not OpenBLAS: its threads are not the library's to check" << std::endl;
    return true;
  }
  const bmr::TetrahedralMesh mesh = bmr::test::StructuredCube(15, 1.0);
  const auto                 solve = [&mesh] {
    bmr::LinearElasticModel model(mesh, { { 1, { 10.0, 0.3 } } });
    model.SetDirichletConditions(BottomNodes(mesh), {});
    return model.Solve(SpreadForces(mesh.points.size()));
  };
  bmr::ConfigureNumerics({ 2 });
  const std::vector<double> hosted = solve();
  const int                 threadsAfter = bmr::BlasThreads();
  bmr::ConfigureNumerics({ 1 });
  const double difference = RelativeDifference(hosted, solve());
  std::cout << "OpenBLAS threads after a solve with 2: " << threadsAfter << "; relative difference to one thread "
            << difference << std::endl;
  return Expect(threadsAfter == 2, "a solve leaves the host's BLAS thread count as it was") &&
         Expect(difference <= 1e-12, "the host's BLAS threads change the displacements by rounding only");
}

/** The factorization (bmr::fem::SupernodalFactorizer) and the triangular solves (bmr::fem::SupernodalSolver) on 2,
 * 3 and 8 threads give the one-thread displacements bit for bit, on a cube whose elimination tree is cut into eight
 * bins below the top separators (16^3 nodes, two materials; the root supernode, 1113 columns, is factorized in six
 * tiles), for a load spread over every node, at two moduli of the second material: the second is a refactorization
 * on the same analysis. 3 threads do not divide the eight bins evenly and 8 run every bin at once. The bins hold at
 * least half of the factor (0.62 measured), so the comparison is not between serial runs. The residual |f - K u| on
 * the free dofs is at most 1e-10 of |f|: a backward-stable Cholesky factorization and solve leave about the unit
 * roundoff times |K| |u| (1e-13 here), so the bound fails only for a wrong factor or solve (a missing or doubled
 * update, or a bin's accumulated updates subtracted twice or not at all, gives order 1). */
bool
CheckThreadCountSolves()
{
  const bmr::TetrahedralMesh                            mesh = bmr::test::StructuredCube(15, 1.0, 2);
  const std::vector<std::int32_t>                       bottom = BottomNodes(mesh);
  const std::vector<double>                             forces = SpreadForces(mesh.points.size());
  const std::map<std::int32_t, bmr::MaterialParameters> materials{ { 1, { 10.0, 0.35 } }, { 2, { 50.0, 0.45 } } };
  const unsigned                                        threadCounts[] = { 1, 2, 3, 8 };
  std::vector<std::unique_ptr<bmr::LinearElasticModel>> models;
  for (const unsigned threads : threadCounts)
  {
    models.push_back(std::make_unique<bmr::LinearElasticModel>(mesh, materials));
    models.back()->SetDirichletConditions(bottom, {});
    models.back()->SetNumberOfSolveThreads(threads);
  }
  bool ok = true;
  for (const double modulus : { 50.0, 80.0 })
  {
    std::vector<std::vector<double>> u;
    for (const auto & m : models)
    {
      m->SetYoungsModulus(2, modulus);
      u.push_back(m->Solve(forces));
      ok &=
        bmr::test::Expect(m->UsesTreeCutFactorization(), "the tree-cut factorization factorizes (not CHOLMOD's own)");
    }
    const double relative = RelativeResidual(*models[0], forces, u[0]);
    const double share = models[0]->GetParallelSolveShare();
    std::cout << "E2 = " << modulus << " kPa: relative residual " << relative << "; share of the factor in the bins "
              << share << "; equal to one thread's bit for bit on";
    for (std::size_t k = 1; k < models.size(); ++k)
    {
      std::cout << " " << threadCounts[k] << " threads: " << (u[k] == u[0]);
      ok &= bmr::test::Expect(
        u[k] == u[0], std::to_string(threadCounts[k]) + " solve threads give the one-thread displacements bit for bit");
    }
    std::cout << std::endl;
    ok &= bmr::test::Expect(share >= 0.5,
                            "the bins hold at least half of the factor (got " + bmr::test::ToString(share) + ")");
    ok &= bmr::test::Expect(
      relative <= 1e-10, "the solve's relative residual is at most 1e-10 (got " + bmr::test::ToString(relative) + ")");
  }
  return ok;
}
/** The tree-cut factorization against CHOLMOD's own (LinearElasticModel::SetReferenceFactorization()), on random
 * stiffness matrices: cubes of 12^3 to 16^3 cells with every node moved by up to 0.2 cells, each element given one of
 * five labels at random, each label a modulus drawn log-uniformly from 5 to 500 kPa and a Poisson's ratio from 0.2
 * to 0.45 (three seeds). Their factors hold separators of several tiles with rows below them, so every kind of
 * top supernode is tiled. Each solve's relative residual |f - K u| / |f| is at most 1e-10 (backward stable: about
 * the unit roundoff times the growth, 1e-13; a lost or doubled update gives order 1), and the two displacements
 * agree to 1e-10 relative: two backward-stable solves differ by about the condition number times the unit
 * roundoff (measured 2e-15 to 2e-14), so the bound leaves room for condition numbers up to 1e6 and fails for any
 * update missed or misplaced. The tree cut's solves on 1 and 5 threads are the same bits. */
bool
CheckAgainstCholmod()
{
  using bmr::test::Expect;
  using bmr::test::ToString;
  bool ok = true;
  for (const unsigned seed : { 1U, 2U, 3U })
  {
    std::mt19937                           random(seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    const int                              cells = 12 + 2 * static_cast<int>(seed - 1);
    bmr::TetrahedralMesh                   mesh = bmr::test::StructuredCube(cells, 1.0);
    const std::vector<std::int32_t>        bottom = BottomNodes(mesh); // before the nodes move
    for (double & x : mesh.points)
    {
      x += 0.2 * (unit(random) - 0.5) * 2.0;
    }
    for (std::int32_t & label : mesh.labels)
    {
      label = 1 + static_cast<std::int32_t>(unit(random) * 5.0) % 5;
    }
    std::map<std::int32_t, bmr::MaterialParameters> materials;
    for (std::int32_t label = 1; label <= 5; ++label)
    {
      materials[label] = { 5.0 * std::pow(100.0, unit(random)), 0.2 + 0.25 * unit(random) };
    }
    const std::vector<double>        forces = SpreadForces(mesh.points.size());
    std::vector<std::vector<double>> u;
    std::vector<double>              residuals;
    for (const unsigned threads : { 1U, 5U, 0U }) // 0: CHOLMOD's own
    {
      bmr::LinearElasticModel model(mesh, materials);
      model.SetDirichletConditions(bottom, {});
      model.SetNumberOfSolveThreads(threads);
      model.SetReferenceFactorization(threads == 0);
      u.push_back(model.Solve(forces));
      residuals.push_back(RelativeResidual(model, forces, u.back()));
      ok &= Expect(model.UsesTreeCutFactorization() == (threads != 0),
                   "the factorization is the one asked for (" + std::string(threads ? "tree cut" : "CHOLMOD") + ")");
    }
    const double difference = RelativeDifference(u[0], u[2]);
    std::cout << "seed " << seed << " (" << cells << "^3 cells): residuals tree cut " << residuals[0] << ", CHOLMOD "
              << residuals[2] << "; relative difference " << difference << "; 1 and 5 threads equal " << (u[0] == u[1])
              << std::endl;
    ok &= Expect(residuals[0] <= 1e-10 && residuals[2] <= 1e-10,
                 "both factorizations solve K u = f to 1e-10 (got " + ToString(residuals[0]) + " and " +
                   ToString(residuals[2]) + ")");
    ok &= Expect(difference <= 1e-10, "the tree cut agrees with CHOLMOD to 1e-10 (got " + ToString(difference) + ")");
    ok &= Expect(u[0] == u[1], "the tree cut gives the same bits on 1 and 5 threads");
  }
  return ok;
}

/** Refactorizations that keep the part of the factor a changed modulus does not reach: a stiff inclusion (label 2,
 * the elements centred in [9, 14]^3 of a 15^3 cube, a corner away from the fixed bottom) whose modulus changes
 * recomputes only the supernodes holding its entries and their ancestors (GetRefactorizedShare() < 1; 1 would mean a
 * whole factorization). Checked:
 * - each factor solves its own K: relative residual |f - K u| / |f| <= 1e-10 (a backward-stable factorization and
 *   solve leave about 1e-13; a missing, stale or doubled update gives order 1, as would a kept part from other
 *   moduli);
 * - the displacements agree with a model that factorizes the same moduli whole, to 1e-9 relative (the same sums in
 *   another order: rounding times the condition number, measured about 1e-13);
 * - the same bits on one thread and three, and the same bits for E2 = 80 kPa before and after E2 = 120 kPa (the
 *   refactorization depends on the moduli, not on the factorizations before it);
 * - a change of the other label's modulus is a whole factorization (share 1) that learns it as the changing label;
 *   the inclusion's next change is whole again, the one after it partial. */
bool
CheckKeptFixedPartRefactorization()
{
  using bmr::test::Expect;
  using bmr::test::ToString;
  bmr::TetrahedralMesh mesh = bmr::test::StructuredCube(15, 1.0);
  for (std::size_t e = 0; e < mesh.labels.size(); ++e)
  {
    bool inside = true;
    for (int c = 0; c < 3; ++c)
    {
      double centroid = 0.0;
      for (int a = 0; a < 4; ++a)
      {
        centroid += 0.25 * mesh.points[3 * static_cast<std::size_t>(mesh.tetrahedra[4 * e + a]) + c];
      }
      inside = inside && centroid > 9.0 && centroid < 14.0;
    }
    mesh.labels[e] = inside ? 2 : 1;
  }
  const std::vector<std::int32_t>                       bottom = BottomNodes(mesh);
  const std::vector<double>                             forces = SpreadForces(mesh.points.size());
  const std::map<std::int32_t, bmr::MaterialParameters> materials{ { 1, { 10.0, 0.35 } }, { 2, { 50.0, 0.45 } } };
  bmr::LinearElasticModel                               one(mesh, materials), three(mesh, materials);
  for (bmr::LinearElasticModel * m : { &one, &three })
  {
    m->SetDirichletConditions(bottom, {});
    m->SetRefactorizationThreshold(0.0); // every change factorizes
  }
  one.SetNumberOfSolveThreads(1);
  three.SetNumberOfSolveThreads(3);
  struct Step
  {
    std::int32_t label;
    double       modulus;
    bool         whole; // expected: a whole factorization
  };
  const Step          steps[] = { { 2, 80.0, true }, { 2, 120.0, false }, { 2, 80.0, false },
                                  { 1, 20.0, true }, { 2, 60.0, true },   { 2, 70.0, false } };
  bool                ok = true;
  std::vector<double> first80;
  for (const Step & step : steps)
  {
    one.SetYoungsModulus(step.label, step.modulus);
    three.SetYoungsModulus(step.label, step.modulus);
    const std::vector<double>                       u1 = one.Solve(forces), u3 = three.Solve(forces);
    std::map<std::int32_t, bmr::MaterialParameters> current = materials;
    current[1].youngsModulus = one.GetYoungsModulus(1);
    current[2].youngsModulus = one.GetYoungsModulus(2);
    bmr::LinearElasticModel whole(mesh, current);
    whole.SetDirichletConditions(bottom, {});
    const double share = one.GetRefactorizedShare(), residual = RelativeResidual(one, forces, u1);
    const double difference = RelativeDifference(u1, whole.Solve(forces));
    std::cout << "E" << step.label << " = " << step.modulus << " kPa: share refactorized " << share
              << ", relative residual " << residual << ", difference to a whole factorization " << difference
              << ", three threads equal bit for bit " << (u1 == u3) << std::endl;
    ok &= Expect(step.whole ? share == 1.0 : share > 0.0 && share < 0.9,
                 std::string(step.whole ? "a whole factorization" : "a partial refactorization") + " (share " +
                   ToString(share) + ")");
    ok &= Expect(residual <= 1e-10, "the factor solves K u = f to 1e-10 (got " + ToString(residual) + ")");
    ok &= Expect(difference <= 1e-9,
                 "the displacements match a whole factorization to 1e-9 (got " + ToString(difference) + ")");
    ok &= Expect(u1 == u3, "three threads give the one-thread displacements bit for bit");
    if (step.label == 2 && step.modulus == 80.0)
    {
      if (first80.empty())
      {
        first80 = u1;
      }
      else
      {
        ok &= Expect(u1 == first80, "E2 = 80 kPa gives the same bits after E2 = 120 kPa as before it");
      }
    }
  }
  return ok;
}

/** Solves observing some dofs only (LinearElasticModel::Solve() with observed dofs) on the 16^3 cube held at its
 * bottom, two materials, with forces on the top face alone and the side x = 15 moved (prescribed on the model's
 * constrained dofs as a second set of held nodes):
 * - the whole solve of this sparse right-hand side (whose forward solve skips the supernodes no load reaches) has a
 *   relative residual of at most 1e-10, as in CheckThreadCountSolves(): a skipped supernode a load reached gives
 *   order 1;
 * - observing the nodes of the corner x, y <= 3, the observed and the constrained dofs equal the whole solve's bit for
 *   bit, on one thread and on eight (the same operations, skipping only supernodes nothing observed needs);
 * - every other free dof is 0, and at least a quarter of the free dofs are (the backward solve skipped their
 *   supernodes; none is 0 in the whole solve);
 * - an observed dof out of range is refused. */
bool
CheckObservedSolves()
{
  using bmr::test::Expect;
  using bmr::test::ToString;
  const bmr::TetrahedralMesh mesh = bmr::test::StructuredCube(15, 1.0, 2);
  std::vector<std::int32_t>  held = BottomNodes(mesh), observed;
  std::vector<double>        forces(mesh.points.size(), 0.0), prescribed(mesh.points.size(), 0.0);
  for (std::size_t n = 0; n < mesh.GetNumberOfPoints(); ++n)
  {
    const double * x = &mesh.points[3 * n];
    if (x[2] == 15.0)
    {
      forces[3 * n] = 0.2 * std::sin(0.3 * static_cast<double>(n));
      forces[3 * n + 2] = -1.0;
    }
    if (x[0] == 15.0 && x[2] > 0.0)
    {
      held.push_back(static_cast<std::int32_t>(n));
      prescribed[3 * n] = -0.1 * x[2] / 15.0;
    }
    if (x[0] <= 3.0 && x[1] <= 3.0)
    {
      observed.insert(observed.end(), { 3 * static_cast<std::int32_t>(n) + 2, 3 * static_cast<std::int32_t>(n) });
    }
  }
  std::sort(held.begin(), held.end());
  const std::map<std::int32_t, bmr::MaterialParameters> materials{ { 1, { 10.0, 0.35 } }, { 2, { 50.0, 0.45 } } };
  bmr::LinearElasticModel                               one(mesh, materials), eight(mesh, materials);
  for (bmr::LinearElasticModel * m : { &one, &eight })
  {
    m->SetDirichletConditions(held, {});
  }
  eight.SetNumberOfSolveThreads(8);
  const std::vector<double> whole = one.Solve(forces, prescribed);
  const std::vector<double> part1 = one.Solve(forces, prescribed, observed);
  const std::vector<double> part8 = eight.Solve(forces, prescribed, observed);
  const std::vector<char> & constrained = one.GetConstrainedDegreesOfFreedom();
  std::vector<char>         isObserved(whole.size(), 0);
  for (const std::int32_t dof : observed)
  {
    isObserved[dof] = 1;
  }
  bool        equal = part1 == part8, othersZero = true;
  std::size_t free = 0, zero = 0, wholeZero = 0;
  for (std::size_t i = 0; i < whole.size(); ++i)
  {
    if (isObserved[i] || constrained[i])
    {
      equal = equal && part1[i] == whole[i];
      continue;
    }
    ++free;
    zero += part1[i] == 0.0 ? 1 : 0;
    wholeZero += whole[i] == 0.0 ? 1 : 0;
  }
  const double residual = RelativeResidual(one, forces, whole);
  std::cout << "observed solves: " << observed.size() << " dofs observed; residual " << residual << "; " << zero
            << " of " << free << " other free dofs skipped (0); equal bit for bit " << equal << std::endl;
  bool ok = Expect(residual <= 1e-10, "the sparse right-hand side solves to 1e-10 (got " + ToString(residual) + ")");
  ok &= Expect(equal, "the observed and constrained dofs equal the whole solve's bit for bit, on one thread and eight");
  ok &= Expect(wholeZero == 0 && 4 * zero >= free,
               "at least a quarter of the other free dofs are skipped (got " + ToString(zero) + " of " +
                 ToString(free) + ")");
  for (std::size_t i = 0; i < whole.size(); ++i)
  {
    othersZero = othersZero && (isObserved[i] || constrained[i] || part1[i] == 0.0 || part1[i] == whole[i]);
  }
  ok &= Expect(othersZero, "every other free dof is 0 or, computed as an ancestor's, the whole solve's value");
  ok &= bmr::test::ExpectException(
    "an observed dof out of range",
    [&] { one.Solve(forces, prescribed, std::vector<std::int32_t>{ static_cast<std::int32_t>(whole.size()) }); },
    "out of range");
  return ok;
}
} // namespace

int
bmrLinearElasticModelTest(int, char *[])
{
  using bmr::test::Expect;
  using bmr::test::ExpectException;
  using bmr::test::ToString;
  bool ok = CheckBlasLeftToHost(); // first: a library that pinned the BLAS would do it at its first factorization
  ok &= CheckSerialOpenMP();       // then: it counts the process's threads
  ok &= CheckThreadCountSolves();
  ok &= CheckAgainstCholmod();
  ok &= CheckKeptFixedPartRefactorization();
  ok &= CheckObservedSolves();

  // 1. Patch test: u = A x + b on the boundary reproduces it exactly inside (P1 elements contain linear fields).
  {
    const bmr::TetrahedralMesh mesh = bmr::test::StructuredCube(6, 2.0);
    const double               A[3][3] = { { 0.01, -0.02, 0.005 }, { 0.03, 0.0, -0.01 }, { -0.004, 0.02, 0.015 } };
    const double               b[3] = { 0.5, -0.25, 1.0 };
    std::vector<std::int32_t>  nodes;
    std::vector<double>        values, exact(mesh.points.size());
    for (std::size_t n = 0; n < mesh.GetNumberOfPoints(); ++n)
    {
      const double * x = &mesh.points[3 * n];
      for (int r = 0; r < 3; ++r)
      {
        exact[3 * n + r] = A[r][0] * x[0] + A[r][1] * x[1] + A[r][2] * x[2] + b[r];
      }
      const bool boundary = x[0] == 0 || x[1] == 0 || x[2] == 0 || x[0] == 12 || x[1] == 12 || x[2] == 12;
      if (boundary)
      {
        nodes.push_back(static_cast<std::int32_t>(n));
        values.insert(values.end(), &exact[3 * n], &exact[3 * n + 3]);
      }
    }
    bmr::LinearElasticModel model(mesh, { { 1, { 10.0, 0.3 } } });
    model.SetDirichletConditions(nodes, values);
    const std::vector<double> u = model.Solve({});
    const double              err = RelativeDifference(u, exact);
    std::cout << "patch test relative error " << err << std::endl;
    // 1e-10: the linear field is in the element space, so only rounding remains.
    ok &= Expect(err <= 1e-10, "patch test exact to a relative 1e-10 (got " + ToString(err) + ")");
  }

  // 2. Scale invariance: u(10^k E, 10^k F) = u(E, F).
  {
    const bmr::TetrahedralMesh mesh = bmr::test::StructuredCube(5, 2.0, 2);
    std::vector<std::int32_t>  bottom;
    std::vector<double>        forces(mesh.points.size(), 0.0);
    for (std::size_t n = 0; n < mesh.GetNumberOfPoints(); ++n)
    {
      if (mesh.points[3 * n + 2] == 0.0)
      {
        bottom.push_back(static_cast<std::int32_t>(n));
      }
      if (mesh.points[3 * n + 2] == 10.0)
      {
        forces[3 * n] = 0.3;
        forces[3 * n + 2] = -1.0;
      }
    }
    std::vector<double> reference;
    double              worst = 0.0;
    for (int k = -6; k <= 6; ++k)
    {
      const double            s = std::pow(10.0, k);
      bmr::LinearElasticModel model(mesh, { { 1, { 10.0 * s, 0.35 } }, { 2, { 50.0 * s, 0.4 } } });
      model.SetDirichletConditions(bottom, {});
      std::vector<double> f(forces);
      for (double & v : f)
      {
        v *= s;
      }
      const std::vector<double> u = model.Solve(f);
      if (k == -6)
      {
        reference = u;
      }
      worst = std::max(worst, RelativeDifference(u, reference));
      if (k == 0)
      {
        // Equilibrium: the reactions balance the applied load (sum of forces = 0).
        const std::vector<double> r = model.ComputeReactionForces(u, f);
        double                    sum[3] = { 0, 0, 0 }, applied = 0.0;
        for (std::size_t i = 0; i < r.size(); ++i)
        {
          sum[i % 3] += r[i] + f[i];
          applied += std::abs(f[i]);
        }
        const double imbalance = std::sqrt(sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]) / applied;
        std::cout << "force imbalance " << imbalance << std::endl;
        ok &= Expect(imbalance < 1e-10, // rounding only
                     "reactions balance the applied load to a relative 1e-10 (got " + ToString(imbalance) + ")");
        // The cached factorization: a second right-hand side reuses it and doubles u.
        std::vector<double> f2(f);
        for (double & v : f2)
        {
          v *= 2.0;
        }
        const double        factorizeBefore = model.GetTimings().factorize;
        std::vector<double> u2 = model.Solve(f2);
        for (double & v : u2)
        {
          v *= 0.5;
        }
        const double doubled = RelativeDifference(u2, u);
        ok &=
          Expect(doubled < 1e-12, "twice the load gives twice u to a relative 1e-12 (got " + ToString(doubled) + ")");
        ok &= Expect(model.GetTimings().factorize == factorizeBefore,
                     "a second right-hand side reuses the factorization (factorize time " + ToString(factorizeBefore) +
                       " s -> " + ToString(model.GetTimings().factorize) + " s)");
      }
    }
    ok &= CheckRefactorizationThreshold(mesh, bottom, forces);
    std::cout << "scale invariance: worst relative difference over k = -6..6: " << worst << std::endl;
    // 1e-10: exact in exact arithmetic; the factorization's rounding is scale-free.
    ok &= Expect(worst <= 1e-10,
                 "u invariant under (E, F) -> 10^k (E, F) to a relative 1e-10 (got " + ToString(worst) + ")");
  }

  // 2b. The free-constrained block (ComputeCouplingForces, and Solve's K_fc g_c) against the whole matrix: bit for
  // bit, since both sum A_ij x_j in ascending j and the skipped terms are exact zeros; one material averaged, so
  // that the patch couplings are in the block too.
  {
    const bmr::TetrahedralMesh mesh = bmr::test::StructuredCube(4, 2.5, 2);
    bmr::MaterialParameters    averaged{ 40.0, 0.45 };
    averaged.formulation = bmr::ElementFormulationEnum::NodalAveragedPressure;
    bmr::LinearElasticModel   model(mesh, { { 1, { 10.0, 0.3 } }, { 2, averaged } });
    std::vector<std::int32_t> held;
    std::vector<double>       prescribed(mesh.points.size(), 0.0), v(mesh.points.size(), 0.0);
    for (std::size_t n = 0; n < mesh.GetNumberOfPoints(); ++n)
    {
      const double z = mesh.points[3 * n + 2];
      for (int c = 0; c < 3; ++c)
      {
        const double wave = std::sin(1.7 * double(n) + c); // any values, nonzero
        (z == 0.0 || z == 10.0 ? prescribed : v)[3 * n + c] = (z == 10.0 ? 0.3 : 1.0) * wave;
      }
      if (z == 0.0 || z == 10.0)
      {
        held.push_back(static_cast<std::int32_t>(n));
      }
    }
    model.SetDirichletConditions(held, {});
    const std::vector<double> whole = model.ComputeInternalForces(v), block = model.ComputeCouplingForces(v);
    std::size_t               differ = 0;
    for (std::size_t i = 0; i < v.size(); ++i)
    {
      const bool constrained = model.GetConstrainedDegreesOfFreedom()[i] != 0;
      differ += constrained ? block[i] != whole[i] : block[i] != 0.0;
    }
    ok &=
      Expect(differ == 0,
             "K_cf v_f equals K v at the constrained dofs bit for bit, 0 elsewhere (" + ToString(differ) + " differ)");
    // Solve with prescribed values: K u = f on the free dofs, to rounding (1e-12 of the largest term).
    std::vector<double> f(mesh.points.size(), 0.0);
    f[f.size() / 2] = 0.7;
    const std::vector<double> u = model.Solve(f, prescribed);
    const std::vector<double> Ku = model.ComputeInternalForces(u);
    double                    residual = 0.0, scale = 0.0;
    for (std::size_t i = 0; i < u.size(); ++i)
    {
      scale = std::max(scale, std::abs(Ku[i]));
      if (!model.GetConstrainedDegreesOfFreedom()[i])
      {
        residual = std::max(residual, std::abs(Ku[i] - f[i]));
      }
    }
    ok &= Expect(residual <= 1e-12 * scale,
                 "K u = f on the free dofs with prescribed values (residual " + ToString(residual) + ", scale " +
                   ToString(scale) + ")");
  }

  // 2c. The free dofs are numbered in a nested-dissection order of the node graph (fem::
  // NumberFreeDofsByNestedDissection), which depends on how the mesh numbers its nodes: the same problem with the
  // nodes numbered backwards gives the same displacements, to rounding (1e-12 relative: the factors differ only in
  // the order of their sums).
  {
    const bmr::TetrahedralMesh mesh = bmr::test::StructuredCube(5, 2.0, 2);
    bmr::TetrahedralMesh       reversed = mesh;
    const std::size_t          N = mesh.GetNumberOfPoints();
    const auto                 back = [N](std::size_t n) { return N - 1 - n; };
    for (std::size_t n = 0; n < N; ++n)
    {
      std::copy(&mesh.points[3 * n], &mesh.points[3 * n + 3], &reversed.points[3 * back(n)]);
    }
    for (std::int32_t & node : reversed.tetrahedra)
    {
      node = static_cast<std::int32_t>(back(static_cast<std::size_t>(node)));
    }
    std::vector<std::int32_t> bottom, bottomReversed;
    std::vector<double>       f(3 * N, 0.0), fReversed(3 * N, 0.0);
    for (std::size_t n = 0; n < N; ++n)
    {
      if (mesh.points[3 * n + 2] == 0.0)
      {
        bottom.push_back(static_cast<std::int32_t>(n));
        bottomReversed.push_back(static_cast<std::int32_t>(back(n)));
      }
      if (mesh.points[3 * n + 2] == 10.0)
      {
        f[3 * n] = fReversed[3 * back(n)] = 0.2;
        f[3 * n + 2] = fReversed[3 * back(n) + 2] = -0.5;
      }
    }
    const std::map<std::int32_t, bmr::MaterialParameters> materials{ { 1, { 10.0, 0.3 } }, { 2, { 60.0, 0.45 } } };
    bmr::LinearElasticModel                               a(mesh, materials), b(reversed, materials);
    a.SetDirichletConditions(bottom, {});
    b.SetDirichletConditions(bottomReversed, {});
    const std::vector<double> ua = a.Solve(f), ub = b.Solve(fReversed);
    std::vector<double>       ubInA(3 * N);
    for (std::size_t n = 0; n < N; ++n)
    {
      std::copy(&ub[3 * back(n)], &ub[3 * back(n) + 3], &ubInA[3 * n]);
    }
    const double difference = RelativeDifference(ubInA, ua);
    ok &= Expect(difference <= 1e-12,
                 "the same u whatever the node numbering, to a relative 1e-12 (got " + ToString(difference) + ")");
  }

  // 3. Error paths, each with a message naming the cause.
  const bmr::TetrahedralMesh                            cube = bmr::test::StructuredCube(2, 1.0, 2);
  const std::map<std::int32_t, bmr::MaterialParameters> good{ { 1, { 10, 0.3 } }, { 2, { 20, 0.3 } } };
  ok &= ExpectException(
    "nu = 0.5",
    [&] {
      bmr::LinearElasticModel m(cube, { { 1, { 10, 0.5 } }, { 2, { 20, 0.3 } } });
    },
    "label 1: Poisson's ratio");
  ok &= ExpectException(
    "E = 0",
    [&] {
      bmr::LinearElasticModel m(cube, { { 1, { 10, 0.3 } }, { 2, { 0, 0.3 } } });
    },
    "label 2: Young's modulus");
  ok &= ExpectException(
    "E = NaN",
    [&] {
      bmr::LinearElasticModel m(cube, { { 1, { NAN, 0.3 } }, { 2, { 1, 0.3 } } });
    },
    "label 1: Young's modulus");
  ok &= ExpectException(
    "missing material",
    [&] {
      bmr::LinearElasticModel m(cube, { { 1, { 10, 0.3 } } });
    },
    "has label 2, which has no material");
  ok &= ExpectException(
    "no Dirichlet",
    [&] {
      bmr::LinearElasticModel m(cube, good);
      m.Solve({});
    },
    "rigid-body motion");
  ok &= ExpectException(
    "collinear Dirichlet",
    [&] {
      bmr::LinearElasticModel m(cube, good);
      m.SetDirichletConditions({ 0, 1, 2 }, {}); // three nodes on the x axis
      m.Solve({});
    },
    "rigid-body motion");
  {
    bmr::TetrahedralMesh inverted = cube;
    std::swap(inverted.tetrahedra[4 * 5], inverted.tetrahedra[4 * 5 + 1]);
    ok &= ExpectException(
      "inverted element", [&] { bmr::LinearElasticModel m(inverted, good); }, "element 5 (label 1) is inverted");
    bmr::TetrahedralMesh degenerate = cube;
    degenerate.tetrahedra[4 * 3 + 1] = degenerate.tetrahedra[4 * 3];
    ok &= ExpectException(
      "degenerate element", [&] { bmr::LinearElasticModel m(degenerate, good); }, "element 3 (label 1) is degenerate");
    bmr::TetrahedralMesh orphan = cube;
    orphan.points.insert(orphan.points.end(), { 50.0, 50.0, 50.0 });
    ok &= ExpectException(
      "orphan node", [&] { bmr::LinearElasticModel m(orphan, good); }, "belongs to no element");
    bmr::TetrahedralMesh nanPoint = cube;
    nanPoint.points[4] = NAN;
    ok &= ExpectException(
      "NaN coordinate", [&] { bmr::LinearElasticModel m(nanPoint, good); }, "node 1 has a non-finite coordinate");
  }
  ok &= ExpectException(
    "bad Dirichlet node",
    [&] {
      bmr::LinearElasticModel m(cube, good);
      m.SetDirichletConditions({ 999 }, {});
    },
    "Dirichlet node index 999");
  ok &= ExpectException(
    "NaN force",
    [&] {
      bmr::LinearElasticModel m(cube, good);
      m.SetDirichletConditions({ 0, 1, 3, 9 }, {});
      std::vector<double> f(cube.points.size(), 0.0);
      f.back() = NAN;
      m.Solve(f);
    },
    "is not finite");
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}
