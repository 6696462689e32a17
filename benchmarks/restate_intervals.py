"""Restates the rows of run_calibration_benchmark.sh runs as the current interval rule would state them from their
first N rescans (itk::ModulusInterval with the rescans' calibrated half-widths; UncertaintySettings::correctBias
off): centre the fit, spread s the SD of the rescans' log E or, when some stopped on a search bound, the larger of
that and the censored normal fit's sigma x sqrt(n / (n - 1)) (itk::FitCensoredNormal), half-widths
from itk::RescanCalibrations (the largest calibrated count not above N, scaled by Student's ratio), and the ends the images
do not determine set to the search bounds. A rescan's random numbers depend only on the seed and its index, so the
first N rescans of a run are those a run with N rescans makes: the rows are what the current binary would report.
Usage: restate_intervals.py RUNS.csv OUT.csv [N (default 4)] [TAG_SUFFIX (default -restatedN)] [K68,K95]
K68,K95: half-widths for N rescans other than RescanCalibrations' (to check constants fixed on another run).
The search bounds are the pelvis scene's, 20 and 600 kPa."""
import csv
import math
import os
import sys

LOWER, UPPER = 20.0, 600.0
CALIBRATIONS = ((4, 0.7826, 1.4996),)  # itkBiomechanicalPipelines.h, RescanCalibrations (session 45)


def student_quantile(p, dof):
    """Student's t quantile: the density integrated by Simpson's rule, inverted by bisection (as the C++)."""
    norm = math.lgamma((dof + 1) / 2) - math.lgamma(dof / 2) - 0.5 * math.log(dof * math.pi)

    def half_cdf(t):
        h = t / 2000
        f = [math.exp(norm - (dof + 1) / 2 * math.log1p((k * h) ** 2 / dof)) for k in range(2001)]
        return h / 3 * (f[0] + f[-1] + sum((4 if k % 2 else 2) * f[k] for k in range(1, 2000)))

    lo, hi = 0.0, 100.0
    while hi - lo > 1e-8:
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if half_cdf(mid) < p - 0.5 else (lo, mid)
    return (lo + hi) / 2


def student_half_widths(n):
    root = math.sqrt(1 + 1 / n)
    return [student_quantile(p, n - 1) * root for p in (0.84, 0.975)]


def censored_sigma(logs, lower, upper):
    """The censored normal maximum-likelihood sigma by expectation-maximization (None: fewer than two distinct
    uncensored values)."""
    seen = [x for x in logs if lower < x < upper]
    if len(seen) < 2 or min(seen) == max(seen):
        return None
    n = len(logs)
    mu = sum(logs) / n
    sigma = math.sqrt(sum((x - mu) ** 2 for x in logs) / n)
    for _ in range(10000):
        first = second = 0.0
        for x in logs:
            if lower < x < upper:
                first, second = first + x, second + x * x
                continue
            above = x >= upper
            m = mu if above else -mu
            a = ((upper if above else -lower) - m) / sigma
            tail = 0.5 * math.erfc(a / math.sqrt(2))
            lam = a + 1 / a if tail < 1e-300 else math.exp(-a * a / 2) / math.sqrt(2 * math.pi) / tail
            mean = m + sigma * lam
            variance = sigma * sigma * max(0.0, 1 + a * lam - lam * lam)
            first += mean if above else -mean
            second += variance + mean * mean
        next_mu = first / n
        next_sigma = math.sqrt(max(second / n - next_mu * next_mu, 0.0))
        settled = abs(next_mu - mu) < 1e-12 * sigma and abs(next_sigma - sigma) < 1e-12 * sigma
        mu, sigma = next_mu, next_sigma
        if settled or sigma <= 0:
            break
    return sigma


def restate(r, n, suffix):
    fit = float(r["fit_kPa"])
    resamples = [float(x) for x in r["resamples_kPa"].split(";")][:n]
    logs = [math.log(x) for x in resamples]
    lower, upper = math.log(1.001 * LOWER), math.log(0.999 * UPPER)
    lower_reached = fit <= 1.001 * LOWER or any(x <= lower for x in logs)
    upper_reached = fit >= 0.999 * UPPER or any(x >= upper for x in logs)
    mean = sum(logs) / n
    s = math.sqrt(sum((x - mean) ** 2 for x in logs) / (n - 1))
    if lower_reached or upper_reached:
        sc = censored_sigma(logs, lower, upper)
        s = max(s, sc * math.sqrt(n / (n - 1))) if sc is not None else s
    count, k68, k95 = ([c for c in CALIBRATIONS if c[0] <= n] or [CALIBRATIONS[0]])[-1]
    ratio = [a / b for a, b in zip(student_half_widths(n), student_half_widths(count))]
    k68, k95 = k68 * ratio[0], k95 * ratio[1]
    c = math.log(fit)
    lo_det = not (lower_reached or c - k95 * s <= lower)
    hi_det = not (upper_reached or c + k95 * s >= upper)
    out = dict(r, tag=r["tag"] + suffix, resamples=str(n), resamples_kPa=";".join(f"{x:.3f}" for x in resamples),
               sigma_log_E=f"{s:.4f}", quantiles="calibrated", bias_corrected="0",
               estimate_kPa=f"{min(max(fit, LOWER), UPPER):.3f}",
               lower_determined="1" if lo_det else "0", upper_determined="1" if hi_det else "0")
    for k, lo_key, hi_key in ((k68, "lo68_kPa", "hi68_kPa"), (k95, "lo95_kPa", "hi95_kPa")):
        lo = min(max(math.exp(c - k * s), LOWER), UPPER) if lo_det else LOWER
        hi = max(min(math.exp(c + k * s), UPPER), LOWER) if hi_det else UPPER
        out[lo_key], out[hi_key] = f"{min(lo, UPPER):.3f}", f"{max(hi, LOWER):.3f}"
    return out


def main():
    runs_csv, out_csv = sys.argv[1:3]
    n = int(sys.argv[3]) if len(sys.argv) > 3 else 4
    suffix = sys.argv[4] if len(sys.argv) > 4 else f"-restated{n}"
    if len(sys.argv) > 5:  # other constants for n rescans
        global CALIBRATIONS
        CALIBRATIONS = ((n, *map(float, sys.argv[5].split(","))),)
    rows = [r for r in csv.DictReader(open(runs_csv)) if r.get("resamples_kPa")]
    with open(out_csv + ".tmp", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        writer.writeheader()
        for r in rows:
            writer.writerow(restate(r, n, suffix))
    os.replace(out_csv + ".tmp", out_csv)


if __name__ == "__main__":
    main()
