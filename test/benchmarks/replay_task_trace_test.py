#!/usr/bin/env python3
"""benchmarks/replay_task_trace.py on hand-made traces whose replays are known exactly (tolerance 1e-9 s: the
replay adds and compares the given durations, no rounding beyond the floats')."""
import os
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "benchmarks"))
import replay_task_trace as replay  # noqa: E402

HEADER = "kind,thread,id,parent,budget,worker,start_s,end_s,name\n"


def trace(rows):
    f = tempfile.NamedTemporaryFile("w", suffix=".csv", delete=False)
    f.write(HEADER + "".join(",".join(str(x) for x in r) + "\n" for r in rows))
    f.close()
    return replay.Trace(f.name)


def expect(trace_, p, expected, what):
    got = replay.predict(trace_, p)
    ok = abs(got - expected) <= 1e-9
    print(f"{'ok' if ok else 'FAIL'}: {what}, P = {p}: {got:.6f} s (expected {expected})")
    return ok


ok = True
# 1 s serial, four 1 s tasks on 2 threads (2 s), 1 s serial: 6 s on one worker, 3 s on four or more.
flat = trace([("region", 0, 0, -1, 2, 0, 1.0, 3.0, "r"),
              ("task", 0, 1, 0, 0, 0, 1.0, 2.0, ""), ("task", 1, 2, 0, 0, 1, 1.0, 2.0, ""),
              ("task", 0, 3, 0, 0, 0, 2.0, 3.0, ""), ("task", 1, 4, 0, 0, 1, 2.0, 3.0, ""),
              ("end", 0, -1, -1, 0, 0, 0, 4.0, "")])
ok &= expect(flat, 1, 6.0, "four tasks, serial around")
ok &= expect(flat, 2, 4.0, "four tasks, as recorded")
ok &= expect(flat, 4, 3.0, "four tasks, one worker each")
ok &= expect(flat, 16, 3.0, "four tasks, more workers than tasks")
# A background of 3 s from 0.5 s; the recording thread waits for it from 1.0 to 3.5 s and ends at 4.0 s:
# beside it 4.0 s, on one worker the wait does its 3 s (1.0 + 3.0 + 0.5).
beside = trace([("background", 1, 0, -1, 1, 0, 0.5, 3.5, "mesh"), ("wait", 0, 1, -1, 1, 0, 1.0, 3.5, "mesh"),
                ("end", 0, -1, -1, 0, 0, 0, 4.0, "")])
ok &= expect(beside, 2, 4.0, "a background waited for")
ok &= expect(beside, 1, 4.5, "a background on one worker")
# Two 2 s resamples on 2 threads, each with a nested region of four 0.5 s tasks on one thread: with 8 workers
# each resample gets 4 (8 // 2) and takes 0.5 s; with 2, as recorded, 2 s.
rows = [("region", 0, 0, -1, 2, 0, 0.0, 2.0, "resamples")]
for k, (task, nested) in enumerate([(1, 2), (7, 8)]):
    rows.append(("task", k, task, 0, 0, k, 0.0, 2.0, ""))
    rows.append(("region", k, nested, task, 1, 0, 0.0, 2.0, "solve"))
    rows += [("task", k, nested + 1 + i, nested, 0, 0, 0.5 * i, 0.5 * (i + 1), "") for i in range(4)]
rows.append(("end", 0, -1, -1, 0, 0, 0, 2.0, ""))
nested = trace(rows)
ok &= expect(nested, 2, 2.0, "nested regions, as recorded")
ok &= expect(nested, 8, 0.5, "nested regions, a share of the workers each")
ok &= expect(nested, 1, 4.0, "nested regions, one worker")
sys.exit(0 if ok else 1)
