#!/usr/bin/env python3
"""Reads what scripts/gpu-bench.sh wrote under OUT_DIR and writes OUT_DIR/summary.md: each of the
performance targets with the figure that decides it, the fragment pipeline against compute per mode,
the Bunny's frame rates with the rebuild counted, the GPU builds against the CPU's, and the animated
mesh's frame split into its parts, with refits against rebuilds.

    scripts/gpu-bench-summary.py OUT_DIR
    scripts/gpu-bench-summary.py --self-test   # checks the arithmetic on made-up results

A target is judged only where the run measured its conditions (20K spheres, 1920x1080, 1M
primitives, 1M animated triangles); a missing benchmark (a step that failed or ran out of time) is named, not guessed.
Exits 1 if a results file cannot be read, 2 on bad arguments.
"""

import json
import os
import re
import sys
import tempfile
from pathlib import Path

BRUTE_TARGET = 200.0  # best BVH mode over brute force at 20K spheres, same adapter
BUNNY_FPS_TARGET = 500.0  # Bunny, 20K spheres, 1920x1080, depth 5, rebuilt every frame
BUILD_MS_TARGET = 1.0  # 1M primitives on the GPU
MOTION_MS_TARGET = 2.0  # 1M animated triangles skinned and rebuilt on the GPU, a frame
PIPELINES = ("fragment", "compute")


def load_results(folder):
    """The rows of a bench's results.json, or None where the step left none."""
    path = folder / "results.json"
    if not path.is_file():
        return None
    return read_json(path, path.read_text())


def read_json(path, text, line=None):
    try:
        return json.loads(text)
    except ValueError as e:
        where = f"{path}, line {line}" if line else f"{path}"
        raise ValueError(f"{where}: {e}") from None


def fps_with_build(row):
    """Frames per second with the BVH rebuild counted, where the bench rebuilt it."""
    return 1e3 / (row["ms_median"] + (row["build_ms_median"] or 0.0))


def fmt(value, digits=1):
    return f"{value:,.{digits}f}"


def best_over_brute(bvh_rows, brute_rows):
    """Per (resolution, pipeline): the largest sphere count both benches ran, the best BVH mode
    there and its speed-up over brute force (trace time alone, as brute force builds nothing)."""
    out = []
    for pipeline in PIPELINES:
        brute = {r["count"]: r for r in brute_rows if r["pipeline"] == pipeline}
        bvh = [r for r in bvh_rows if r["pipeline"] == pipeline and r["count"] in brute]
        if not bvh:
            continue
        count = max(r["count"] for r in bvh)
        best = min((r for r in bvh if r["count"] == count), key=lambda r: r["ms_median"])
        out.append((pipeline, count, best["accel"], brute[count]["ms_median"] / best["ms_median"]))
    return out


def pipeline_ratios(rows):
    """(count, accel, fragment ms, compute ms, compute / fragment) where both pipelines ran."""
    by_key = {(r["count"], r["accel"], r["pipeline"]): r["ms_median"] for r in rows}
    out = []
    for count, accel in sorted({(r["count"], r["accel"]) for r in rows}):
        fragment = by_key.get((count, accel, "fragment"))
        compute = by_key.get((count, accel, "compute"))
        if fragment and compute:
            out.append((count, accel, fragment, compute, compute / fragment))
    return out


def morton_bits(builder):
    match = re.search(r"(\d+)-bit", builder)
    return int(match.group(1)) if match else None


def build_pairs(builds):
    """(primitives, bits, GPU build, CPU build or None) for every GPU build."""
    key = lambda b: (b["primitives"], morton_bits(b["builder"]))  # noqa: E731
    cpu = {key(b): b for b in builds if b["device"].startswith("cpu")}
    return [(*key(b), b, cpu.get(key(b))) for b in builds if b["device"].startswith("gpu")]


def verdict(met):
    return "**met**" if met else "**not met**"


def summarise(out):
    head = ["# gpu-bench summary", ""]
    info = out / "info.txt"
    if info.is_file():
        head += ["Adapters (`raypipe info`, first line of each):", ""]
        head += [f"- {line}" for line in info.read_text().splitlines() if line and not line.startswith(" ")]
        head.append("")
    missing = []
    targets = []

    # The tables; the targets they decide go above them.
    lines = ["## Figure 4: the best BVH mode against brute force", ""]
    lines += ["Trace time per frame (median), the BVH modes rebuilding their tree every frame.", ""]
    figure_sizes = sorted(
        {p.name[len("figure4-") : -len("-bvh")] for p in out.glob("figure4-*-bvh")},
        key=lambda s: -int(s.split("x")[0]),
    )
    for size in figure_sizes:
        bvh = load_results(out / f"figure4-{size}-bvh")
        brute = load_results(out / f"figure4-{size}-brute")
        if bvh is None or brute is None:
            missing.append(f"figure 4 at {size}")
            continue
        for pipeline, count, accel, speedup in best_over_brute(bvh, brute):
            lines.append(f"- {size}, {pipeline}: at {count:,} spheres {accel} is {fmt(speedup)}x brute force")
            if count == 20000:
                targets.append(
                    f"Best BVH mode at least {BRUTE_TARGET:.0f}x brute force at 20K spheres ({size}, {pipeline}): "
                    f"{fmt(speedup)}x, {verdict(speedup >= BRUTE_TARGET)}"
                )
        lines += ["", f"The fragment pipeline against compute at {size}:", ""]
        lines += [
            "| spheres | accel | fragment ms | compute ms | compute / fragment |",
            "| ---: | --- | ---: | ---: | ---: |",
        ]
        for count, accel, fragment, compute, ratio in pipeline_ratios(bvh + brute):
            lines.append(f"| {count:,} | {accel} | {fmt(fragment, 3)} | {fmt(compute, 3)} | {ratio:.2f} |")
        lines.append("")

    lines += ["## The Bunny, rebuilt every frame", ""]
    for name, title in (("bunny-spheres", "spheres"), ("bunny-triangles", "triangles")):
        rows = load_results(out / name)
        if rows is None:
            missing.append(f"the Bunny as {title}")
            continue
        r0 = rows[0]
        lines += [f"As {r0['count']:,} {title}, {r0['width']}x{r0['height']}:", ""]
        lines += [
            "| pipeline | accel | trace ms | build ms | fps with the build | Mrays/s |",
            "| --- | --- | ---: | ---: | ---: | ---: |",
        ]
        for r in rows:
            lines.append(
                f"| {r['pipeline']} | {r['accel']} | {fmt(r['ms_median'], 3)} | {fmt(r['build_ms_median'] or 0.0, 3)} "
                f"| {fmt(fps_with_build(r))} | {fmt(r['mrays_per_s'])} |"
            )
        lines.append("")
        best = {
            p: max((fps_with_build(r) for r in rows if r["pipeline"] == p), default=None) for p in PIPELINES
        }
        if best["fragment"] and best["compute"]:
            lines += [
                f"Best fps with the build: fragment {fmt(best['fragment'])}, compute {fmt(best['compute'])} "
                f"(compute / fragment {best['compute'] / best['fragment']:.2f}).",
                "",
            ]
        faster = max((v for v in best.values() if v), default=None)
        if (
            title == "spheres"
            and faster
            and r0["count"] == 20000
            and (r0["width"], r0["height"]) == (1920, 1080)
        ):
            targets.append(
                f"Bunny, 20K spheres, 1920x1080, rebuilt every frame, above {BUNNY_FPS_TARGET:.0f} fps in the "
                f"faster pipeline: {fmt(faster)} fps, {verdict(faster > BUNNY_FPS_TARGET)}"
            )

    lines += ["## The Bunny's triangles over a tree built once: the LBVH against binned SAH", ""]
    by_builder = {b: load_results(out / f"bunny-triangles-{b}") for b in ("lbvh", "sah")}
    if None in by_builder.values():
        missing.append("the Bunny's triangles over a tree built once")
    else:
        r0 = by_builder["lbvh"][0]
        lines += [
            f"{r0['width']}x{r0['height']}, fragment pipeline, trace ms:",
            "",
            "| accel | LBVH | SAH | SAH / LBVH |",
            "| --- | ---: | ---: | ---: |",
        ]
        sah = {r["accel"]: r["ms_median"] for r in by_builder["sah"]}
        for r in by_builder["lbvh"]:
            if r["accel"] in sah:
                ratio = sah[r["accel"]] / r["ms_median"]
                lines.append(f"| {r['accel']} | {fmt(r['ms_median'], 3)} | {fmt(sah[r['accel']], 3)} | {ratio:.2f} |")
        lines.append("")

    lines += ["## LBVH builds, GPU against CPU", ""]
    builds_path = out / "builds.jsonl"
    builds = []
    if builds_path.is_file():
        for number, line in enumerate(builds_path.read_text().splitlines(), 1):
            if line.strip():
                builds.append(read_json(builds_path, line, number))
    if not builds:
        missing.append("the LBVH builds")
    else:
        lines += [
            "| primitives | codes | GPU ms (morton, sort, hierarchy) | GPU Mprims/s | CPU ms | GPU / CPU |",
            "| ---: | ---: | ---: | ---: | ---: | ---: |",
        ]
        for n, bits, gpu, cpu in build_pairs(builds):
            ms = gpu["build_ms"]
            phases = f"{fmt(ms['total'], 3)} ({fmt(ms['morton'], 3)}, {fmt(ms['sort'], 3)}, {fmt(ms['hierarchy'], 3)})"
            cpu_ms = cpu["build_ms"]["total"] if cpu else None
            ratio = f"{ms['total'] / cpu_ms:.2f}" if cpu_ms else "-"
            lines.append(
                f"| {n:,} | {bits}-bit | {phases} | {fmt(gpu['mprims_per_s'])} | {fmt(cpu_ms, 3) if cpu_ms else '-'} | {ratio} |"
            )
            if n == 1_000_000:
                targets.append(
                    f"1M primitives built on the GPU in at most {BUILD_MS_TARGET:.0f} ms ({bits}-bit codes): "
                    f"{fmt(ms['total'], 3)} ms, {verdict(ms['total'] <= BUILD_MS_TARGET)}"
                )
        gpu_builders = sorted({b["builder"] for b in builds if b["device"].startswith("gpu")})
        lines += [""] + [f"GPU builder: {builder}" for builder in gpu_builders] + [""]

    lines += summarise_ray_queries(out)

    motion_lines, motion_targets = summarise_motion(out)
    lines += motion_lines
    targets += motion_targets

    head += ["## Targets", ""]
    head += [f"- {t}" for t in targets] or ["- none at the sizes of this run (`--quick` measures none)"]
    head += [f"- not measured: {m} (see log.txt)" for m in missing]
    head.append("")
    # Whole or not at all: a full disk leaves no half summary.
    partial = out / "summary.md.partial"
    partial.write_text("\n".join(head + lines) + "\n")
    os.replace(partial, out / "summary.md")
    return targets, missing


def summarise_ray_queries(out):
    """The driver's structures walked by ray queries (figure4-SIZE-rayquery,
    bunny-triangles-rayquery-ORDER) beside the best BVH walk of the same run, where the adapter had
    ray queries."""
    lines = []
    figures = sorted(out.glob("figure4-*-rayquery"))
    bunnies = sorted(out.glob("bunny-triangles-rayquery-*"))
    if not figures and not bunnies:
        return lines
    lines += ["## The driver's ray queries beside the BVH walks", ""]
    lines += [
        "Trace and build (BLASes and TLAS, rebuilt every frame) per frame, medians, beside the fastest "
        "BVH walk's trace at the same count and pipeline in this run; the last column is rayquery's "
        "speed over the walk's (above 1: the driver's structures trace faster).",
        "",
    ]
    lines += [
        "| scene | pipeline | rayquery trace ms | rayquery build ms | best walk | its trace ms | rayquery speed / walk's |",
        "| --- | --- | ---: | ---: | --- | ---: | ---: |",
    ]
    pairs = [(f, out / f.name.replace("-rayquery", "-bvh")) for f in figures]
    pairs += [(b, out / "bunny-triangles") for b in bunnies]
    for folder, walks_folder in pairs:
        rows = load_results(folder)
        walks = load_results(walks_folder) or []
        if rows is None:
            lines.append(f"| {folder.name}: no results (see log.txt) |")
            continue
        for r in rows:
            same = [w for w in walks if w["count"] == r["count"] and w["pipeline"] == r["pipeline"]]
            best = min(same, key=lambda w: w["ms_median"], default=None)
            scene = f"{folder.name}, {r['count']:,}"
            walk = f"| {best['accel']} | {fmt(best['ms_median'], 3)} | {best['ms_median'] / r['ms_median']:.2f} |" if best else "| - | - | - |"
            lines.append(
                f"| {scene} | {r['pipeline']} | {fmt(r['ms_median'], 3)} | {fmt(r['build_ms_median'] or 0.0, 3)} {walk}"
            )
    lines.append("")
    return lines


def summarise_motion(out):
    """The animated mesh's points (motion-N/motion.json): the frame's parts, and the refit's trace
    against the rebuild's; the target where 1M triangles were run."""
    lines, targets = [], []
    folders = sorted(out.glob("motion-*"), key=lambda p: int(p.name.split("-")[1]))
    if not folders:
        return lines, targets
    lines += ["## An animated skinned mesh, posed and rebuilt every frame", ""]
    lines += [
        "| triangles | pipeline | accel | eval ms | skin ms | build ms | trace ms | (skin + build) / frame | refit ms | trace refitted / rebuilt |",
        "| ---: | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    for folder in folders:
        path = folder / "motion.json"
        if not path.is_file():
            lines.append(f"| {folder.name}: no results (see log.txt) |")
            continue
        for p in read_json(path, path.read_text())["points"]:
            refit = fmt(p["refit_ms"], 3) if p.get("refit_ms") is not None else "-"
            ratio = fmt(p["refit_trace_ratio_last"], 2) if p.get("refit_trace_ratio_last") is not None else "-"
            lines.append(
                f"| {p['triangles']:,} | {p['pipeline']} | {p['accel']} | {fmt(p['eval_ms'], 3)} | {fmt(p['skin_ms'], 3)} | "
                f"{fmt(p['build_ms'], 3)} | {fmt(p['trace_ms'], 3)} | {fmt(100 * p['motion_share'])} % | {refit} | {ratio} |"
            )
            if p["triangles"] >= 1_000_000 and p["memory"] == "storage":
                moved = p["skin_ms"] + p["build_ms"]
                targets.append(
                    f"1M animated triangles skinned and rebuilt in under {MOTION_MS_TARGET:.0f} ms a frame "
                    f"({p['pipeline']}, {p['accel']}): {fmt(moved, 3)} ms, {verdict(moved < MOTION_MS_TARGET)}"
                )
    lines.append("")
    return lines, targets


def self_test():
    """Made-up results with known answers: the speed-up, the ratio, the fps with the build and the
    verdicts must come out as computed by hand here."""

    def row(count, pipeline, accel, ms, build=None, size=(1920, 1080)):
        return {
            "count": count,
            "pipeline": pipeline,
            "accel": accel,
            "width": size[0],
            "height": size[1],
            "ms_median": ms,
            "build_ms_median": build,
            "mrays_per_s": 1.0,
        }

    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        for name, rows in {
            "figure4-1920x1080-bvh": [
                row(20000, "fragment", "stack", 2.0, 0.5),
                row(20000, "fragment", "threaded", 1.0, 0.5),
                row(20000, "compute", "threaded", 0.5, 0.5),
                row(50000, "compute", "threaded", 0.7, 0.6),
            ],
            "figure4-1920x1080-brute": [
                row(20000, "fragment", "brute", 150.0),
                row(20000, "compute", "brute", 120.0),
            ],
            "bunny-spheres": [
                row(20000, "fragment", "threaded", 1.5, 0.5),
                row(20000, "compute", "threaded", 1.0, 0.25),
            ],
            "bunny-triangles-lbvh": [row(69451, "fragment", "stack", 2.0), row(69451, "fragment", "threaded", 3.0)],
            "bunny-triangles-sah": [row(69451, "fragment", "stack", 1.5), row(69451, "fragment", "threaded", 3.3)],
            "figure4-1920x1080-rayquery": [row(20000, "fragment", "rayquery", 0.25, 0.75)],
        }.items():
            (out / name).mkdir()
            (out / name / "results.json").write_text(json.dumps(rows))
        build = lambda device, bits, total: {  # noqa: E731
            "primitives": 1_000_000,
            "device": device,
            "builder": f"lbvh ({bits}-bit Morton codes)",
            "build_ms": {"morton": 0.1, "sort": 0.2, "hierarchy": 0.3, "total": total},
            "mprims_per_s": 1e3 / total,
        }
        (out / "builds.jsonl").write_text(
            "\n".join(
                json.dumps(b)
                for b in [
                    build("gpu: x", 30, 0.8),
                    build("cpu (16 threads)", 30, 8.0),
                    build("gpu: x", 63, 1.2),
                ]
            )
        )
        motion = lambda triangles, skin, build: {  # noqa: E731
            "triangles": triangles,
            "pipeline": "fragment",
            "accel": "threaded",
            "memory": "storage",
            "eval_ms": 0.01,
            "skin_ms": skin,
            "build_ms": build,
            "trace_ms": 4.0,
            "motion_share": (skin + build) / (skin + build + 4.01),
            "refit_ms": 0.5,
            "refit_trace_ratio_last": 1.05,
        }
        for name, point in {"motion-100000": motion(100_128, 0.25, 0.5), "motion-1000000": motion(1_000_404, 0.5, 1.25)}.items():
            (out / name).mkdir()
            (out / name / "motion.json").write_text(json.dumps({"points": [point], "refit": []}))
        targets, missing = summarise(out)
        text = (out / "summary.md").read_text()
    expected_targets = [
        "Best BVH mode at least 200x brute force at 20K spheres (1920x1080, fragment): 150.0x, **not met**",
        "Best BVH mode at least 200x brute force at 20K spheres (1920x1080, compute): 240.0x, **met**",
        "Bunny, 20K spheres, 1920x1080, rebuilt every frame, above 500 fps in the faster pipeline: 800.0 fps, **met**",
        "1M primitives built on the GPU in at most 1 ms (30-bit codes): 0.800 ms, **met**",
        "1M primitives built on the GPU in at most 1 ms (63-bit codes): 1.200 ms, **not met**",
        "1M animated triangles skinned and rebuilt in under 2 ms a frame (fragment, threaded): 1.750 ms, **met**",
    ]
    failures = [t for t in expected_targets if t not in targets]
    for needle in (
        "| 20,000 | threaded | 1.000 | 0.500 | 0.50 |",
        "compute / fragment 1.60",
        "| 1,000,000 | 30-bit | 0.800 (0.100, 0.200, 0.300) | 1,250.0 | 8.000 | 0.10 |",
        "not measured: the Bunny as triangles",
        "| stack | 2.000 | 1.500 | 0.75 |",
        "| threaded | 3.000 | 3.300 | 1.10 |",
        "| 100,128 | fragment | threaded | 0.010 | 0.250 | 0.500 | 4.000 | 15.8 % | 0.500 | 1.05 |",
        "| figure4-1920x1080-rayquery, 20,000 | fragment | 0.250 | 0.750 | threaded | 1.000 | 4.00 |",
    ):
        if needle not in text:
            failures.append(needle)
    if missing != ["the Bunny as triangles"]:
        failures.append(f"missing: {missing}")
    if failures:
        print("gpu-bench-summary self-test failed; not found:", *failures, sep="\n  ", file=sys.stderr)
        print(text, file=sys.stderr)
        return 1
    print("gpu-bench-summary self-test: ok")
    return 0


def main(argv):
    if argv == ["--self-test"]:
        return self_test()
    if len(argv) != 1 or not Path(argv[0]).is_dir():
        print(
            "usage: scripts/gpu-bench-summary.py OUT_DIR | --self-test (OUT_DIR: a gpu-bench.sh output folder)",
            file=sys.stderr,
        )
        return 2
    out = Path(argv[0])
    try:
        targets, missing = summarise(out)
    except (OSError, ValueError, KeyError, TypeError) as e:
        print(f"gpu-bench-summary: cannot read the results: {e}", file=sys.stderr)
        return 1
    print(f"summary: {out / 'summary.md'} ({len(targets)} targets judged, {len(missing)} benchmarks missing)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
