"""What the benchmarks' summaries share about a row of run_calibration_benchmark.sh: whether its stated
statement (an interval, or a one-sided bound when an end is not determined) covers the truth; and writing a
summary table."""
import csv


def covers(r, lo, hi):
    """Whether the statement covers the truth: an interval, or a one-sided bound when an end is not determined."""
    E = float(r["true_E_kPa"])
    lower_ok = r["lower_determined"] == "0" or E >= lo
    upper_ok = r["upper_determined"] == "0" or E <= hi
    return lower_ok and upper_ok


def determined(r):
    """Whether both ends of the row's interval were determined (no bound stated)."""
    return r["lower_determined"] == "1" and r["upper_determined"] == "1"


def write_table(path, table):
    """\a table (a list of dicts with the same keys) as CSV, floats to 4 decimals."""
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(table[0].keys()))
        w.writeheader()
        for row in table:
            w.writerow({k: f"{v:.4f}" if isinstance(v, float) else v for k, v in row.items()})
