#!/usr/bin/env python3
"""Predicts a run's wall time on P workers by replaying its task trace (biomechreg --task-trace FILE).

The trace holds the recording thread's timeline (0 to the "end" row), the regions of independent tasks the
library ran (each with the thread budget the program gave it, each task's span and the regions nested in it), the
spans of work other threads did alongside (background) and the recording thread's waits for them. The replay:

- a task lasts what it was measured to last, minus its nested regions' measured walls plus their replayed ones;
- a region lasts the makespan of its tasks on its workers, each task in order to the first free worker (TBB
  deals them out dynamically), plus the overhead measured beyond its makespan at its recorded budget;
- a top-level region recorded with budget b at P0 threads gets max(1, round(b P / P0)) workers, as the program
  gives its fine solves its budget and its sweep the share beside the background mesh; a region nested in a task
  of a region of w workers and n tasks gets max(1, w // min(w, n)), the resamples' equal share;
- what lies in neither regions nor waits is serial and stays as measured; a background span runs beside the
  recording thread from where that thread reached its start, and a wait lasts until that span's replayed end,
  plus what the waiting thread did after the background had ended (its own work inside the wait); on one
  worker nothing runs beside, and the wait does the background's work.

It assumes a task's duration does not depend on how many run at once: memory bandwidth shared by more cores, the
BLAS's speed and the machine's caches are not modelled. Compare the prediction for the recorded thread count with
a measured run before reading the others.

Usage: replay_task_trace.py TRACE.csv [P ...]   (prints one line per P: predicted seconds)
"""
import csv
import gzip
import heapq
import sys
from collections import defaultdict


class Trace:
    def __init__(self, path):
        self.regions, self.tasks, self.backgrounds, self.waits = {}, {}, [], []
        self.end, self.main = 0.0, 0
        with (gzip.open(path, "rt") if path.endswith(".gz") else open(path)) as f:
            for row in csv.DictReader(f):
                kind = row["kind"]
                start, end = float(row["start_s"]), float(row["end_s"])
                thread, rid, parent = int(row["thread"]), int(row["id"]), int(row["parent"])
                if kind == "region":
                    self.regions[rid] = dict(thread=thread, parent=parent, budget=int(row["budget"]), start=start,
                                             end=end, name=row["name"], tasks=[])
                elif kind == "task":
                    self.tasks[rid] = dict(region=parent, start=start, end=end, nested=[])
                elif kind == "background":
                    self.backgrounds.append(dict(thread=thread, start=start, end=end, name=row["name"]))
                elif kind == "wait":
                    self.waits.append(dict(thread=thread, parent=parent, start=start, end=end, name=row["name"]))
                elif kind == "end":
                    self.end, self.main = end, thread
        for tid in sorted(self.tasks):
            self.regions[self.tasks[tid]["region"]]["tasks"].append(tid)
        for rid in sorted(self.regions):
            parent = self.regions[rid]["parent"]
            if parent >= 0:
                self.tasks[parent]["nested"].append(rid)

    def recorded_threads(self):
        """The largest budget of a top-level region: the run's thread count."""
        return max([r["budget"] for r in self.regions.values() if r["parent"] < 0] + [1])


def makespan(durations, workers):
    free = [0.0] * workers
    for d in durations:
        heapq.heappush(free, heapq.heappop(free) + d)
    return max(free)


def task_duration(trace, tid, workers_of_region, task_count):
    task = trace.tasks[tid]
    measured = task["end"] - task["start"]
    inner = max(1, workers_of_region // max(1, min(workers_of_region, task_count)))
    for rid in task["nested"]:
        r = trace.regions[rid]
        measured += region_duration(trace, rid, inner) - (r["end"] - r["start"])
    return max(measured, 0.0)


def region_duration(trace, rid, workers):
    r = trace.regions[rid]
    n = len(r["tasks"])
    if n == 0:
        return r["end"] - r["start"]
    recorded = [trace.tasks[t]["end"] - trace.tasks[t]["start"] for t in r["tasks"]]
    overhead = max(0.0, (r["end"] - r["start"]) - makespan(recorded, max(1, r["budget"])))
    durations = [task_duration(trace, t, workers, n) for t in r["tasks"]]
    return makespan(durations, workers) + overhead


def thread_items(trace, thread, start, end):
    """Top-level regions and waits of a thread within [start, end], in time order."""
    items = [("region", rid, r["start"], r["end"]) for rid, r in trace.regions.items()
             if r["thread"] == thread and r["parent"] < 0 and start <= r["start"] and r["end"] <= end]
    items += [("wait", w["name"], w["start"], w["end"]) for w in trace.waits
              if w["thread"] == thread and w["parent"] < 0 and start <= w["start"] and w["end"] <= end]
    return sorted(items, key=lambda item: item[2])


def scaled_budget(trace, rid, p, p0):
    return max(1, round(trace.regions[rid]["budget"] * p / p0))


class Replay:
    """One replay of a trace on p workers (recorded on p0 threads)."""

    def __init__(self, trace, p, p0):
        self.trace, self.p, self.p0 = trace, p, p0
        self.pending = sorted(trace.backgrounds, key=lambda b: b["start"])
        self.started, self.ended = {}, {}  # background name -> replayed start, end

    def start_backgrounds(self, until, replayed_at):
        while self.pending and self.pending[0]["start"] <= until:
            b = self.pending.pop(0)
            self.started[b["name"]] = replayed_at(b["start"])

    def wait(self, name, start, end, now):
        """The replayed time after the wait [start, end] for background name, reached at replayed time now. What
        the waiting thread did after the background had ended (end - max(start, its end)) was its own work, which
        follows the background's end."""
        span = next((b for b in self.trace.backgrounds if b["name"] == name), None)
        if span is None:
            return now + (end - start)
        if name not in self.ended:
            # On one worker nothing ran beside: the wait does the work.
            begin = now if self.p == 1 else self.started.get(name, now)
            self.ended[name] = self.span(span["thread"], span["start"], span["end"], begin)
        return max(now, self.ended[name]) + max(0.0, end - max(start, span["end"]))

    def span(self, thread, start, end, begin):
        """The replayed time at which a thread's timeline from start to end ends, begun at replayed time begin."""
        now, position = begin, start
        for kind, key, s, e in thread_items(self.trace, thread, start, end):
            gap_start, replayed_gap_start = position, now
            self.start_backgrounds(s, lambda t: replayed_gap_start + (t - gap_start))
            now += s - position
            if kind == "region":
                length = region_duration(self.trace, key, scaled_budget(self.trace, key, self.p, self.p0))
                rate, region_start = (length / (e - s) if e > s else 0.0), now
                self.start_backgrounds(e, lambda t: region_start + (t - s) * rate)
                now += length
            else:
                now = self.wait(key, s, e, now)
            position = e
        gap_start, replayed_gap_start = position, now
        self.start_backgrounds(end, lambda t: replayed_gap_start + (t - gap_start))
        return now + (end - position)


def predict(trace, p, p0=None):
    return Replay(trace, p, p0 or trace.recorded_threads()).span(trace.main, 0.0, trace.end, 0.0)


def breakdown(trace):
    """Seconds of the recording thread by kind: in regions (by name), waiting, and serial."""
    parts = defaultdict(float)
    for kind, key, s, e in thread_items(trace, trace.main, 0.0, trace.end):
        parts[("region: " + trace.regions[key]["name"]) if kind == "region" else "wait: " + key] += e - s
    parts["serial"] = trace.end - sum(parts.values())
    return dict(parts)


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    trace = Trace(sys.argv[1])
    workers = [int(p) for p in sys.argv[2:]] or [1, 2, 4, 8, 16]
    print(f"recorded: {trace.end:.2f} s on {trace.recorded_threads()} threads")
    for p in workers:
        print(f"P = {p:3d}: {predict(trace, p):.2f} s")


if __name__ == "__main__":
    main()
