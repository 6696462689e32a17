"""The thick slices' calibration (itk::SliceCalibrations) from run_calibration_benchmark.sh rows, and its check.

fit [--filling] RUNS.csv [RUNS.csv ...]: per slice thickness (the largest side of the rows' spacing_mm), from all m pairs: the
    line log(fit / 100 kPa) = a + beta log(true E / 100 kPa) with residual SD s, by the censored (Tobit) likelihood
    (a fit on the upper search bound, 600 kPa, says only that the fit would have gone at least there); prints the
    constants for include/itkModulusInterval.h and a markdown table. Needs scipy. --filling: with the bladder's
    volume change between the scans as a second regressor (the rows' bladder_volume_change_ml, or where a row
    predates that column imputed from its drawn wall motion by the relation fitted on the rows that have it).
    Rows on grids rotated about the slice axis are left out (their own check).
tails OUT_DIR FIT.csv [FIT.csv ...] -- CHECK.csv [CHECK.csv ...]: whether the calibration's residuals need a model
    other than the normal line: the normal Tobit line, Student-t residuals (one degrees-of-freedom shared by the
    thicknesses) and the normal line with the bladder's filling as a second covariate, each fitted on FIT and judged
    by its likelihood and by the coverage of its statements on the CHECK pairs (interval, or a bound for a fit on
    the upper search bound; the search range's own limits not applied); writes OUT_DIR/slice_calibration_tails.csv.
check RUNS.csv OUT_DIR: per slice thickness, what register stated on pairs the constants never saw: coverage of the
    68 % and 95 % statements (an interval, or a one-sided bound where an end is not determined), how many bounds
    were stated and were true, how many were not determined, the median |error| of the stated moduli (all and at
    30-150 kPa); writes OUT_DIR/slice_calibration_check.csv and slice_calibration_check.png (reliability diagram
    per thickness; log error of the stated estimate against the true modulus) and prints a markdown table.
"""
import csv
import math
import os
import statistics
import sys
from collections import OrderedDict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from interval_rows import covers, determined, write_table  # noqa: E402

BOUNDS_KPA = (20.0, 600.0)
BOUND_LEVEL = 0.999  # itk::SliceCalibrationBoundLevel


def slice_mm(r):
    return max(float(x) for x in r["spacing_mm"].split("x"))


def by_slice(rows):
    groups = OrderedDict()
    for r in sorted(rows, key=slice_mm):
        groups.setdefault(slice_mm(r), []).append(r)
    return groups


def by_geometry(rows):
    """By slice thickness, the grids rotated about the slice axis (OBLIQUE_DEG) apart: "3", "3 oblique"."""
    groups = OrderedDict()
    for r in sorted(rows, key=lambda r: (slice_mm(r), float(r["rotate_z_deg"] or 0) != 0)):
        oblique = float(r["rotate_z_deg"] or 0) != 0
        groups.setdefault(f"{slice_mm(r):g}" + (" oblique" if oblique else ""), []).append(r)
    return groups


E0_KPA = 100.0  # the reference modulus of the calibration line


def censored_line(log_true, log_fit, censored_at):
    """Maximum-likelihood line log(fit / E0) = a + beta log(E / E0) + N(0, sigma^2) of the pairs' fits against their
    truths, a fit on the upper search bound only known to be at least there (right-censored at \a censored_at:
    the Tobit likelihood); Nelder-Mead from the uncensored least-squares line, to 1e-7 in the parameters (finer than
    the constants' digits matter for the interval)."""
    import numpy as np
    from scipy.optimize import minimize
    from scipy.stats import norm
    x, y = np.array(log_true), np.array(log_fit)
    cens = y >= censored_at - 1e-6

    def nll(p):
        a, beta, log_sigma = p
        mu, sigma = a + beta * x, math.exp(log_sigma)
        return -(norm.logpdf(y[~cens], mu[~cens], sigma).sum() + norm.logsf(censored_at, mu[cens], sigma).sum())

    beta0, a0 = np.polyfit(x[~cens], y[~cens], 1)
    start = [a0, beta0, math.log(np.std(y[~cens] - a0 - beta0 * x[~cens]))]
    best = minimize(nll, start, method="Nelder-Mead", options={"xatol": 1e-7, "fatol": 1e-10, "maxiter": 20000})
    a, beta, log_sigma = best.x
    return a, beta, math.exp(log_sigma), int(cens.sum())


def fit_constants(rows):
    """Every pair counts: a fit that stopped on the upper search bound says only that the fit would have gone at
    least there (right-censored); leaving such pairs out would drop the stiffest fits. The line's slope carries the
    error's growth with E (stiff organs read too stiff by more than soft ones at thick slices)."""
    print("| slices [mm] | pairs | on the upper bound (censored) | a | beta | s |")
    print("|---:|---:|---:|---:|---:|---:|")
    lines = []
    for t, group in by_slice(rows).items():
        log_true = [math.log(float(r["true_E_kPa"]) / E0_KPA) for r in group]
        log_fit = [math.log(float(r["fit_kPa"]) / E0_KPA) for r in group]
        if min(float(r["fit_kPa"]) for r in group) <= 1.001 * BOUNDS_KPA[0]:
            sys.exit("a fit on the lower bound: the censored fit below handles the upper one only")
        m = len(group)
        a, beta, sigma, censored = censored_line(log_true, log_fit, math.log(BOUNDS_KPA[1] / E0_KPA))
        s = sigma * math.sqrt(m / (m - 2))  # the divide-by-n maximum-likelihood SD, as a residual SD of a line
        print(f"| {t:g} | {m} | {censored} | {a:+.4f} | {beta:.4f} | {s:.4f} |")
        lines.append(f"{{ {t:g}, {a:.4f}, {beta:.4f}, {s:.4f}, {m} }}")
    print("constexpr SliceCalibration SliceCalibrations[] = { " + ", ".join(lines) + " };")


def filling_relation(rows):
    """The bladder's volume change between the scans [mL] of each row: measured (bladder_volume_change_ml, what
    register reports of the labels) where the row has it, else imputed from the drawn wall motion b [mm] by
    dV = c1 b + c2 b^2 (no motion, no change), least squares over the rows that measured it (the phantom's anatomy
    is the same in every pair, so the drawn motion fixes the change up to voxelization). Prints the relation and
    its residual SD per thickness; returns the function row -> mL."""
    import numpy as np
    measured = [r for r in rows if r.get("bladder_volume_change_ml")]
    if len(measured) < 5:
        sys.exit("the filling term needs rows that measured bladder_volume_change_ml (at least 5)")
    b = np.array([float(r["bladder_mm"]) for r in measured])
    v = np.array([float(r["bladder_volume_change_ml"]) for r in measured])
    (c1, c2), *_ = np.linalg.lstsq(np.c_[b, b * b], v, rcond=None)
    imputed = lambda r: c1 * float(r["bladder_mm"]) + c2 * float(r["bladder_mm"]) ** 2  # noqa: E731
    print(f"bladder volume change = {c1:.3f} mL/mm b + {c2:.4f} mL/mm^2 b^2 ({len(measured)} measured pairs)")
    for t, group in by_slice(measured).items():
        residuals = [float(r["bladder_volume_change_ml"]) - imputed(r) for r in group]
        print(f"  {t:g} mm: {len(group)} pairs, residual SD {statistics.pstdev(residuals):.2f} mL, "
              f"largest {max(map(abs, residuals)):.2f} mL")
    return lambda r: float(r["bladder_volume_change_ml"]) if r.get("bladder_volume_change_ml") else imputed(r)


def scale_line(rows, filling, reference):
    """Maximum-likelihood line with the filling term and a residual SD that varies with the modulus and the filling:
    log(fit / E0) ~ N(a + beta x + gamma z, s^2 exp(2 (c x + d z))), x = log(E / E0), z = dV - V0, censored at the
    upper search bound; Nelder-Mead from the homoscedastic line, restarted once, to 1e-8 in the parameters. Returns
    (a, beta, gamma, s, c, d, m)."""
    import numpy as np
    from scipy.optimize import minimize
    from scipy.stats import norm
    upper = math.log(BOUNDS_KPA[1] / E0_KPA)
    x = np.array([math.log(float(r["true_E_kPa"]) / E0_KPA) for r in rows])
    y = np.array([math.log(float(r["fit_kPa"]) / E0_KPA) for r in rows])
    z = np.array([filling(r) - reference for r in rows])
    cens = y >= upper - 1e-6

    def nll(p):
        a, beta, gamma, log_s, c, d = p
        mu, sd = a + beta * x + gamma * z, np.exp(log_s + c * x + d * z)
        return -(norm.logpdf(y[~cens], mu[~cens], sd[~cens]).sum() + norm.logsf(upper, mu[cens], sd[cens]).sum())

    (a0, beta0, gamma0, s0, _), = student_line({0: rows}, True, lambda r: filling(r) - reference)[0].values()
    best = [a0, beta0, gamma0, math.log(s0), 0.0, 0.0]
    for _ in range(2):
        best = minimize(nll, best, method="Nelder-Mead", options={"maxiter": 60000, "maxfev": 60000, "xatol": 1e-8,
                                                                  "fatol": 1e-11}).x
    a, beta, gamma, log_s, c, d = best
    return a, beta, gamma, math.exp(log_s), c, d, len(rows)


def filling_reference(rows, filling):
    """V0 [mL]: the rows' mean volume change, rounded (it only centres z: the fitted model does not depend on it)."""
    return round(statistics.mean(filling(r) for r in rows))


def fit_filling_constants(rows):
    """Per thickness, the line with the bladder's volume change dV as a second regressor and a residual SD that
    varies with the modulus and dV (scale_line(); the residuals' spread grows with E and shrinks with the filling:
    docs/history/benchmarks.md); V0 the pairs' mean change, rounded; the calibrated range the pairs' own (outward
    to 1 mL). Prints the constants for include/itkModulusInterval.h and a markdown table."""
    filling = filling_relation(rows)
    reference = filling_reference(rows, filling)
    print("| slices [mm] | pairs | on the upper bound | a | beta | gamma [1/mL] | s at E0, V0 | c (per log E) | "
          "d [1/mL] | filling range [mL] |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|")
    lines = []
    for t, group in by_slice(rows).items():
        a, beta, gamma, s, c, d, m = scale_line(group, filling, reference)
        low, high = math.floor(min(map(filling, group))), math.ceil(max(map(filling, group)))
        censored = sum(float(r["fit_kPa"]) >= BOUNDS_KPA[1] - 1e-3 for r in group)
        print(f"| {t:g} | {m} | {censored} | {a:+.4f} | {beta:.4f} | {gamma:+.5f} | {s:.4f} | {c:+.4f} | {d:+.5f} | "
              f"{low}-{high} |")
        lines.append(f"{{ {t:g}, {a:.4f}, {beta:.4f}, {gamma:.6f}, {s:.4f}, {c:.4f}, {d:.6f}, {reference:g}, "
                     f"{{ {low:g}, {high:g} }}, {m} }}")
    print("constexpr SliceCalibration SliceCalibrations[] = { " + ", ".join(lines) + " };")


def student_line(groups, nu_shared, covariate=None):
    """Maximum-likelihood lines per thickness (with \a covariate(row) as a second regressor when given) and
    residuals N(0, sigma^2) (nu_shared None) or Student-t with one fitted degrees-of-freedom for all thicknesses;
    censored at the upper search bound. Returns ({thickness: (a, beta, gamma, sigma, m)}, nu, negative
    log-likelihood)."""
    import numpy as np
    from scipy.optimize import minimize
    from scipy.stats import norm, t as student
    upper = math.log(BOUNDS_KPA[1] / E0_KPA)
    data = []
    for rows in groups.values():
        x = np.array([math.log(float(r["true_E_kPa"]) / E0_KPA) for r in rows])
        y = np.array([math.log(float(r["fit_kPa"]) / E0_KPA) for r in rows])
        z = np.array([covariate(r) if covariate else 0.0 for r in rows])
        data.append((x, y, z, y >= upper - 1e-6))

    def nll(p):
        nu = math.exp(p[-1]) + 1 if nu_shared is None else None
        total = 0.0
        for i, (x, y, z, c) in enumerate(data):
            a, beta, gamma, log_sigma = p[4 * i:4 * i + 4]
            mu, sigma = a + beta * x + gamma * z, math.exp(log_sigma)
            dist = norm(mu, sigma) if nu is None else student(nu, mu, sigma)
            total -= dist.logpdf(y)[~c].sum() + dist.logsf(upper)[c].sum()
        return total

    start = [v for _ in data for v in (0.3, 1.2, 0.0, math.log(0.25))] + ([math.log(4.0)] if nu_shared is None else [])
    best = minimize(nll, start, method="Nelder-Mead", options={"maxiter": 100000, "maxfev": 100000, "xatol": 1e-7,
                                                               "fatol": 1e-10})
    best = minimize(nll, best.x, method="Nelder-Mead", options={"maxiter": 100000, "maxfev": 100000, "xatol": 1e-7,
                                                                "fatol": 1e-10})
    nu = math.exp(best.x[-1]) + 1 if nu_shared is None else math.inf
    lines = {t: (*best.x[4 * i:4 * i + 3], math.exp(best.x[4 * i + 3]), len(rows))
             for i, (t, rows) in enumerate(groups.items())}
    return lines, nu, best.fun


def statement_covers(r, line, nu, covariate, level):
    """Whether the inverted line's statement at \a level covers the truth of row \a r (a bound from a fit on the
    upper search bound); Student's predictive factor sqrt(1 + 1/m), t_(m-2) for normal residuals."""
    from scipy.stats import t as student
    a, beta, gamma, sigma, m = line
    k = student.ppf((1 + level) / 2, nu if math.isfinite(nu) else m - 2) * math.sqrt(1 + 1 / m)
    shift = a + gamma * (covariate(r) if covariate else 0.0)
    fit = float(r["fit_kPa"])
    low = E0_KPA * math.exp((math.log(fit / E0_KPA) - shift - k * sigma) / beta)
    high = math.inf if fit >= 0.999 * BOUNDS_KPA[1] else E0_KPA * math.exp((math.log(fit / E0_KPA) - shift + k * sigma) / beta)
    return low <= float(r["true_E_kPa"]) <= high


def scale_statement_covers(r, params, filling, reference, level):
    """As SliceCalibratedInterval with a spread that varies (scale_line()): whether the set of truths x with
    |y - mu(x)| <= k sigma(x) over the search range, k = t_(m-5) sqrt(1 + 1/m), covers the truth of row \a r; its lower
    end is the crossing of mu + k sigma, its upper end the last crossing of mu - k sigma below the upper bound (none:
    not determined), a fit on the upper bound a lower bound."""
    from scipy.optimize import brentq
    from scipy.stats import t as student
    a, beta, gamma, s, c, d, m = params
    z = filling(r) - reference
    k_at = lambda lev: student.ppf((1 + lev) / 2, m - 5) * math.sqrt(1 + 1 / m)  # noqa: E731
    y = math.log(float(r["fit_kPa"]) / E0_KPA)
    lo_x, hi_x = (math.log(b / E0_KPA) for b in BOUNDS_KPA)
    edge = lambda x, sign, k: a + beta * x + gamma * z + sign * k * s * math.exp(c * x + d * z) - y  # noqa: E731

    def lower_end(k):
        return lo_x if edge(lo_x, 1, k) >= 0 else hi_x if edge(hi_x, 1, k) < 0 else brentq(edge, lo_x, hi_x, (1, k))
    k = k_at(level)
    grid = [hi_x - 0.01 * i for i in range(int((hi_x - lo_x) / 0.01) + 2)]
    upper = hi_x
    if y < math.log(BOUNDS_KPA[1] / E0_KPA) - 1e-6 and edge(hi_x, -1, k) > 0:
        upper = next((brentq(edge, max(x, lo_x), min(x + 0.01, hi_x), args=(-1, k)) for x in grid[1:]
                      if edge(max(x, lo_x), -1, k) <= 0), lo_x)
    # A 95 % bound (no upper end) states its lower end at BOUND_LEVEL, as itk::SliceCalibratedInterval does.
    bound = upper >= hi_x - 1e-9 and level >= 0.95
    lower = lower_end(k_at(BOUND_LEVEL) if bound else k)
    return lower <= math.log(float(r["true_E_kPa"]) / E0_KPA) <= upper


def tails(fit_rows, check_rows, out):
    fit_groups = OrderedDict((t, g) for t, g in by_slice(fit_rows).items() if t in (2.0, 3.0))  # the first models
    bladder = lambda r: float(r["bladder_mm"]) - 6.5  # noqa: E731 (the drawn fillings' middle, 3-10 mm)
    models = [("normal", True, None), ("Student-t, shared nu", None, None), ("normal + bladder filling", True, bladder)]
    table = []
    for name, nu_shared, covariate in models:
        lines, nu, nll = student_line(fit_groups, nu_shared, covariate)
        for t, rows in by_slice(check_rows).items():
            if t not in lines:
                continue
            row = OrderedDict(model=name, slice_mm=t, nu=nu, negative_log_likelihood=nll, sigma=lines[t][3],
                              bladder_per_mm=lines[t][2], check_pairs=len(rows))
            for level in (0.68, 0.95):
                row[f"cover{int(level * 100)}"] = statistics.mean(
                    statement_covers(r, lines[t], nu, covariate, level) for r in rows)
            table.append(row)
    filling = filling_relation(fit_rows + check_rows)
    reference = filling_reference(fit_rows, filling)
    for t, rows in by_slice(check_rows).items():
        group = by_slice(fit_rows).get(t)
        if not group:
            continue
        params = scale_line(group, filling, reference)
        row = OrderedDict(model="normal + bladder volume change, spread by E and filling", slice_mm=t, nu=math.inf,
                          negative_log_likelihood=float("nan"), sigma=params[3], bladder_per_mm=params[2],
                          check_pairs=len(rows))
        for level in (0.68, 0.95):
            row[f"cover{int(level * 100)}"] = statistics.mean(
                scale_statement_covers(r, params, filling, reference, level) for r in rows)
        table.append(row)
    write_table(f"{out}/slice_calibration_tails.csv", table)
    print("| residual model | slices [mm] | nu | -log L (fit pairs) | s (at E0) | per mm of filling | check pairs | 68 % covers "
          "| 95 % covers |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for r in table:
        nll = r["negative_log_likelihood"]  # the last model is fitted per thickness: not comparable, not shown
        print(f"| {r['model']} | {r['slice_mm']:g} | {r['nu']:.1f} | {'-' if math.isnan(nll) else f'{nll:.2f}'} | "
              f"{r['sigma']:.3f} | {'-' if r['model'] != models[2][0] else format(r['bladder_per_mm'], '+.3f')} | "
              f"{r['check_pairs']} | {r['cover68']:.2f} | "
              f"{r['cover95']:.2f} |")


def label(geometry):
    """ "3 oblique" -> "3 mm, oblique"."""
    return geometry.replace(" oblique", " mm, oblique") if geometry.endswith("oblique") else f"{geometry} mm"


def check(rows, out):
    table = []
    for t, group in by_geometry(rows).items():
        stated = [r for r in group if r["not_determined"] != "1"]
        both = [r for r in stated if determined(r)]
        bounds = [r for r in stated if not determined(r)]
        errors = [abs(float(r["estimate_kPa"]) / float(r["true_E_kPa"]) - 1) for r in both]
        soft = [abs(float(r["estimate_kPa"]) / float(r["true_E_kPa"]) - 1) for r in both
                if 30 <= float(r["true_E_kPa"]) <= 150]
        row = OrderedDict(
            slice_mm=t, pairs=len(group), not_determined=len(group) - len(stated), bounds=len(bounds),
            bounds_true=sum(covers(r, float(r["lo95_kPa"]), float(r["hi95_kPa"])) for r in bounds),
            cover68=sum(covers(r, float(r["lo68_kPa"]), float(r["hi68_kPa"])) for r in stated) / max(len(stated), 1),
            cover95=sum(covers(r, float(r["lo95_kPa"]), float(r["hi95_kPa"])) for r in stated) / max(len(stated), 1),
            median_abs_error_pct=100 * statistics.median(errors) if errors else float("nan"),
            median_abs_error_30_150_pct=100 * statistics.median(soft) if soft else float("nan"),
            soft_pairs=len(soft),
            median_inverted=statistics.median(int(r["inverted_elements"]) for r in group if r["inverted_elements"]),
            median_register_s=statistics.median(float(r["register_s"]) for r in group))
        table.append(row)
    write_table(f"{out}/slice_calibration_check.csv", table)  # the runs: *_runs.csv
    print("| slices [mm] | pairs | 95 % covers | 68 % covers | bounds (true) | not determined | median abs. error "
          "(30-150 kPa) | median inverted | register [s] |")
    print("|---:|---:|---:|---:|---:|---:|---|---:|---:|")
    for r in table:
        print(f"| {r['slice_mm']} | {r['pairs']} | {r['cover95']:.2f} | {r['cover68']:.2f} | {r['bounds']} "
              f"({r['bounds_true']}) | {r['not_determined']} | {r['median_abs_error_pct']:.0f} % "
              f"({r['median_abs_error_30_150_pct']:.0f} %, {r['soft_pairs']} pairs) | {r['median_inverted']:.0f} | "
              f"{r['median_register_s']:.1f} |")

    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.5))
    left.plot([0.5, 1], [0.5, 1], "k:", label="ideal")
    for r in table:
        left.plot([0.68, 0.95], [r["cover68"], r["cover95"]], "o-", label=label(r["slice_mm"]) + " slices")
    left.set_xlabel("stated level")
    left.set_ylabel("coverage on unseen pairs")
    left.set_title("Reliability per slice thickness")
    left.legend()
    for t, group in by_geometry(rows).items():
        stated = [r for r in group if r["not_determined"] != "1"]
        left_err = [math.log(float(r["estimate_kPa"]) / float(r["true_E_kPa"])) for r in stated]
        right.scatter([float(r["true_E_kPa"]) for r in stated], left_err, s=14, label=label(t))
    right.axhline(0, color="k", lw=0.5)
    right.set_xscale("log")
    right.set_xlabel("true E [kPa]")
    right.set_ylabel("log(stated estimate / true E)")
    right.set_title("Error of the stated estimate")
    right.legend()
    fig.tight_layout()
    fig.savefig(f"{out}/slice_calibration_check.png", dpi=120)


def read_rows(paths):
    rows = []
    for path in paths:
        with open(path) as f:
            rows += [r for r in csv.DictReader(f) if float(r.get("rotate_z_deg") or 0) == 0]
    return rows


def main(argv):
    if len(argv) < 3 or argv[1] not in ("fit", "check", "tails") or (argv[1] == "check" and len(argv) < 4):
        sys.exit(__doc__)
    if argv[1] == "tails":
        if "--" not in argv:
            sys.exit(__doc__)
        split = argv.index("--")
        tails(read_rows(argv[3:split]), read_rows(argv[split + 1:]), argv[2])
        return
    if argv[1] == "check" and os.path.abspath(argv[2]) == os.path.abspath(f"{argv[3]}/slice_calibration_check.csv"):
        sys.exit("RUNS.csv would be overwritten by the summary: name the runs *_runs.csv")
    if argv[1] == "fit":
        filling = "--filling" in argv
        rows = read_rows([path for path in argv[2:] if path != "--filling"])
        fit_filling_constants(rows) if filling else fit_constants(rows)
    else:
        with open(argv[2]) as f:
            check(list(csv.DictReader(f)), argv[3])


if __name__ == "__main__":
    main(sys.argv)
