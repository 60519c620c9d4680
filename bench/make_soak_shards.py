#!/usr/bin/env python3
"""Stretches the shards of a short real run into the shards of a long soak, for measuring
what `mbstorm merge` costs on an 8-hour test without running one (issue #31 item 2).

    make_soak_shards.py HOURS OUT_DIR RUN.json RUN.hlog [RUN.json RUN.hlog ...]

Each run's interval lines (the real histograms its --hlog wrote, one untagged and one per
operation for each 1 s interval) are repeated in order, interval after interval, until the log
covers HOURS; its JSON says the same: measured and requested duration, one timeline interval
per logged interval (copied from the real ones), and counts that add up to the latencies the
stretched log holds (each real interval's count, as many times as it was repeated). Every
shard keeps its own run id, shard number and start time; they are set equal (the first run's)
so that the shards ran side by side, as a sharded soak does.
"""
import json
import os
import sys


def interval_groups(hlog_path):
    """The log's header lines and its interval lines grouped by start time (in file order)."""
    header, groups, order = [], {}, []
    with open(hlog_path) as f:
        for line in f:
            if line.startswith("#") or line.startswith('"'):
                header.append(line)
                continue
            fields = line.split(",")
            start = fields[1] if line.startswith("Tag=") else fields[0]
            if start not in groups:
                groups[start] = []
                order.append(start)
            groups[start].append(line)
    return header, [groups[s] for s in order]


def retimed(line, start_s):
    fields = line.split(",")
    at = 1 if line.startswith("Tag=") else 0
    if fields[at].startswith("stage:"):
        return line
    fields[at] = f"{start_s:.3f}"
    return ",".join(fields)


def stretch(json_path, hlog_path, seconds, start_epoch_s, out_dir):
    with open(json_path) as f:
        doc = json.load(f)
    header, groups = interval_groups(hlog_path)
    real = doc["timeline"]["intervals"]
    # Whole intervals only: the last of a real run is cut short.
    usable = min(len(groups), len(real)) - 1 if min(len(groups), len(real)) > 1 else 1
    name = os.path.basename(json_path)[: -len(".json")]
    intervals, latencies = [], 0
    with open(os.path.join(out_dir, name + ".hlog"), "w") as out:
        out.writelines(header)
        for k in range(seconds):
            source = k % usable
            for line in groups[source]:
                out.write(retimed(line, float(k)))
            iv = dict(real[source])
            iv["index"], iv["start_offset_s"] = k, float(k)
            intervals.append(iv)
            latencies += real[source]["latency_count"]
    scale = latencies / max(1, doc["latency"]["count"])
    doc["timeline"]["intervals"] = intervals
    doc["run"]["measured_duration_s"] = float(seconds)
    doc["run"]["requested_duration_s"] = float(seconds)
    doc["test"]["measure_start_epoch_s"] = start_epoch_s
    doc["latency"]["count"] = latencies
    for counts in [doc["outcomes"], doc["totals"]] + [
        part for op in doc["operations"] for part in (op["outcomes"], op["totals"])
    ]:
        for key, value in counts.items():
            if isinstance(value, int):
                counts[key] = round(value * scale)
    if len(doc["operations"]) == 1:  # the one operation's counts are the run's
        doc["operations"][0]["outcomes"] = doc["outcomes"]
    with open(os.path.join(out_dir, name + ".json"), "w") as out:
        json.dump(doc, out)


def main():
    if len(sys.argv) < 5 or len(sys.argv) % 2 != 1:
        sys.exit(__doc__)
    seconds = int(float(sys.argv[1]) * 3600)
    out_dir = sys.argv[2]
    os.makedirs(out_dir, exist_ok=True)
    pairs = list(zip(sys.argv[3::2], sys.argv[4::2]))
    with open(pairs[0][0]) as f:
        start = json.load(f)["test"]["measure_start_epoch_s"]
    for json_path, hlog_path in pairs:
        stretch(json_path, hlog_path, seconds, start, out_dir)


if __name__ == "__main__":
    main()
