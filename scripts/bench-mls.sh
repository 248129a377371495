#!/usr/bin/env bash
# Benchmarks the exact MLS surface (issue 6, Wald & Seidel 2005) on the CPU: primary rays at
# WIDTHxHEIGHT (default 512x512) through the core's trace_mls from 1 and 2 threads, on a prt-synth
# sphere and on real models (the Stanford bunny mesh sampled by prt-import, the CGAL kitten), in a
# full view and a zoomed view (WS05 4.1's "full" and "head"); then the gain of each kd-tree
# optimization (WS05 3.4.1 shrinking, 3.4.2 encouraged splits, 3.4.3 post-collapse) in rays/s and
# in WS05 4.3's per-ray statistics (kd traversal steps, cells, surface intersections, splats), and
# the accuracy/speed of the intersection settings (samples per cell k, regula falsi steps).
# Builds nothing: it runs the binaries of an existing build.
#
# Usage: scripts/bench-mls.sh BUILD_DIR [POINTS]
#   BUILD_DIR  a configured and built tree with bin/prt-synth, bin/prt-radii, bin/prt-import,
#              bin/prt-mls and bin/mls-bench (make prt-synth prt-radii prt-import prt-mls mls-bench)
#   POINTS     points of the synthetic sphere (default 100000)
# Environment: REPEAT (default 5) timed runs per measurement (median reported, after one warm-up),
#   WIDTH/HEIGHT (default 512), BUNNY_POINTS (default 200000), DATA (default ../shared/data next to
#   the repository), OUT (folder for the JSON results; default: a temporary folder, removed unless
#   KEEP=1), SKIP_OPT=1 skips the optimization study, TABLES_ONLY=1 (with OUT) re-tabulates the JSON
#   results of an earlier run.
# Rays/s are wall-clock medians on whatever else the machine runs: the load average is printed
# with the results; the per-ray statistics and accuracies do not depend on it.
set -euo pipefail
# shellcheck source=lib/bench-common.sh
. "$(dirname "$0")/lib/bench-common.sh"
bench_args "$@"
points=${2:-100000}
repeat=${REPEAT:-5}
width=${WIDTH:-512}
height=${HEIGHT:-512}
bunny_points=${BUNNY_POINTS:-200000}
here=$(cd "$(dirname "$0")/.." && pwd)
data=${DATA:-$here/../shared/data}
bin=$build/bin
bench_need bench-mls "$build" "prt-synth prt-radii prt-import prt-mls mls-bench" \
    "$bin/prt-synth" "$bin/prt-radii" "$bin/prt-import" "$bin/prt-mls" "$bin/mls-bench"
command -v python3 >/dev/null || { echo "bench-mls: python3 is needed to tabulate the JSON results" >&2; exit 1; }

bench_workdir bench-mls "${OUT:-}"

echo "# MLS surface (WS05), CPU, ${width}x${height} primary rays, median of $repeat runs"
echo "# machine: $(nproc) cores, $(uname -m), $(bench_cpu_model), load average $(bench_load)"
echo "# results (JSON): $work"
echo

opt_configs=(  # prt-mls builds without E(n) (WS05 3.4.2) unless --encourage, since 2026-12-03
    "none|--no-shrink --no-collapse"
    "shrink|--no-collapse"
    "shrink+collapse|"
    "encourage|--no-shrink --no-collapse --encourage"
    "all|--encourage"
    "all,E(n)=WS05|--encourage --encourage-limit 21"
    "until-2026-12-02|--encourage --slices 8 --cost-traversal 1"
    "default,shrink-1-axis|--shrink-axes 1"
    "default-but-shrink|--no-shrink"
    "default-but-collapse|--no-collapse"
)

# TABLES_ONLY=1 with OUT=FOLDER: tabulate the JSON results of an earlier run, measure nothing.
if [ "${TABLES_ONLY:-0}" = 1 ]; then
    [ -n "${OUT:-}" ] || { echo "bench-mls: TABLES_ONLY=1 needs OUT=the folder of an earlier run" >&2; exit 1; }
    models=()
    for m in sphere bunny kitten; do [ -f "$work/$m.default.build.json" ] && models+=("$m"); done
else
# -- models ----------------------------------------------------------------------------------------
models=()
"$bin/prt-synth" sphere -o "$work/sphere.pool" -n "$points" --quiet
"$bin/prt-radii" "$work/sphere.pool" -o "$work/sphere.pool" --quiet
models+=("sphere")
bunny=$data/points/stanford_bunny/reconstruction/bun_zipper.ply
if [ -f "$bunny" ]; then
    "$bin/prt-import" "$bunny" -o "$work/bunny.pool" --sample "$bunny_points" --sample-normals interpolated --quiet
    "$bin/prt-radii" "$work/bunny.pool" -o "$work/bunny.pool" --quiet
    models+=("bunny")
else
    echo "bench-mls: $bunny not found: skipping the bunny" >&2
fi
kitten=$data/points/cgal_kitten/kitten.xyz
if [ -f "$kitten" ]; then
    "$bin/prt-import" "$kitten" -o "$work/kitten.pool" --quiet
    "$bin/prt-radii" "$work/kitten.pool" -o "$work/kitten.pool" --quiet
    models+=("kitten")
else
    echo "bench-mls: $kitten not found: skipping the kitten" >&2
fi

# mls_build MODEL TAG ARGS...: builds the tree, writes $work/MODEL.TAG.pool and .build.json
mls_build() {
    local model=$1 tag=$2
    shift 2
    "$bin/prt-mls" "$work/$model.pool" -o "$work/$model.$tag.pool" --quiet --stats-json "$work/$model.$tag.build.json" "$@"
}
# mls_bench MODEL TAG VIEW THREADS ARGS...: writes $work/MODEL.TAG.VIEW[.ARGS].json
mls_bench() {
    local model=$1 tag=$2 view=$3 threads=$4
    shift 4
    local zoom=1
    [ "$view" = zoom ] && zoom=2.2
    local suffix
    suffix=$(echo "$*" | tr ' -' '_' | tr -s '_')
    "$bin/mls-bench" "$work/$model.$tag.pool" --width "$width" --height "$height" --threads "$threads" \
        --repeat "$repeat" --zoom "$zoom" --json "$work/$model.$tag.$view$suffix.json" --quiet "$@"
}

# -- 1. rays/s and per-ray statistics with the defaults ----------------------------------------------
for m in "${models[@]}"; do
    mls_build "$m" default
    for v in full zoom; do mls_bench "$m" default "$v" 1,2; done
done

# -- 2. the kd-tree optimizations (WS05 3.4, 4.3 "no opt" vs "opt") ----------------------------------
if [ "${SKIP_OPT:-0}" != 1 ]; then
    for m in "${models[@]}"; do
        [ "$m" = kitten ] && continue
        for c in "${opt_configs[@]}"; do
            tag=opt-$(echo "${c%%|*}" | tr ',()=+' '_____')
            # shellcheck disable=SC2086
            mls_build "$m" "$tag" ${c#*|}
            mls_bench "$m" "$tag" zoom 1 --refine 0
        done
    done
fi

# -- 3. intersection settings (samples per cell, regula falsi steps) on the default trees -------------
for m in "${models[@]}"; do
    for s in "--samples 4 --refine 0" "--samples 4 --refine 1" "--samples 4 --refine 2" "--samples 8 --refine 0" "--samples 8 --refine 1"; do
        # shellcheck disable=SC2086
        mls_bench "$m" default zoom 1 $s
    done
done

fi  # TABLES_ONLY

# -- tables ------------------------------------------------------------------------------------------
WORK=$work MODELS="${models[*]}" OPT_CONFIGS="$(printf '%s\n' "${opt_configs[@]}")" SKIP_OPT=${SKIP_OPT:-0} python3 - <<'EOF'
import json, os
work = os.environ["WORK"]
models = os.environ["MODELS"].split()
def load(name):
    p = os.path.join(work, name)
    return json.load(open(p)) if os.path.exists(p) else None
def rate(j, threads, key="rays_per_second"):
    for r in j["runs"]:
        if r["threads"] == threads:
            return r[key]
    return float("nan")

print("## 1. MLS rays/s on the CPU (defaults: support factor 1, k = 4 samples, 1 regula falsi step)")
print()
print("| model | view | points | rays/s 1 thread | rays/s 2 threads | rays/CPU-s (1 thread) | hit % | kd steps | cells | surface isecs | splats | F evals | build s | MB |")
print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
for m in models:
    b = load(f"{m}.default.build.json")
    for v in ("full", "zoom"):
        j = load(f"{m}.default.{v}.json")
        if not j: continue
        pr = j["per_ray"]
        print(f"| {m} | {v} | {b['points']} | {rate(j,1):,.0f} | {rate(j,2):,.0f} | {rate(j,1,'rays_per_cpu_second'):,.0f} | {100*j['hit_fraction']:.1f} | "
              f"{pr['traversal_steps']:.1f} | {pr['cells']:.2f} | {pr['intersections']:.3f} | {pr['splats']:.1f} | "
              f"{pr['evaluations']:.2f} | {b['seconds_total']:.1f} | {b['bytes']/1e6:.1f} |")
print()
print("Accuracy of the default settings (same rays, against 16 samples + 12 regula falsi steps in double):")
print()
print("| model | view | mean abs(dt) / model radius | max | missed | extra | normals deg | vs analytic: mean / max of size (bench) | (reference) | float vs double sums: mean / max abs(dt) | flips |")
print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
for m in models:
    for v in ("full", "zoom"):
        j = load(f"{m}.default.{v}.json")
        if not j or "vs_reference" not in j: continue
        r = j["vs_reference"]
        a = j.get("vs_analytic_bench"); ar = j.get("vs_analytic_reference")
        an = f"{a['mean_over_size']:.2e} / {a['max_over_size']:.2e}" if a else "-"
        arn = f"{ar['mean_over_size']:.2e} / {ar['max_over_size']:.2e}" if ar else "-"
        fd = j["float_vs_double"]
        print(f"| {m} | {v} | {r['mean_dt_over_size']:.2e} | {r['max_dt_over_size']:.2e} | {r['missed']} | {r['extra']} | "
              f"{r['mean_normal_deg']:.3f} | {an} | {arn} | {fd['mean_dt_over_size']:.1e} / {fd['max_dt_over_size']:.1e} | {fd['flips']} |")

if os.environ.get("SKIP_OPT") != "1":
    print()
    print("## 2. kd-tree optimizations (WS05 3.4), zoomed view, 1 thread, WS05's intersection (k = 4, no refinement)")
    print()
    print("| model | tree | rays/s | rays/CPU-s | vs none (CPU) | kd steps | cells | surface isecs | splats | F evals | nodes | leaves (empty) | refs/leaf | build s | mean abs(dt)/radius | missed |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    configs = [c.split("|")[0] for c in os.environ["OPT_CONFIGS"].splitlines() if c]
    for m in models:
        base = None
        for c in configs:
            tag = "opt-" + c.translate(str.maketrans(",()=+", "_____"))
            j = load(f"{m}.{tag}.zoom_refine_0.json"); b = load(f"{m}.{tag}.build.json")
            if not j or not b: continue
            r1 = rate(j, 1); c1 = rate(j, 1, "rays_per_cpu_second")
            if c == "none": base = c1
            pr = j["per_ray"]; vr = j.get("vs_reference", {})
            gain = f"{c1/base:.2f}x" if base else "-"
            print(f"| {m} | {c} | {r1:,.0f} | {c1:,.0f} | {gain} | {pr['traversal_steps']:.1f} | {pr['cells']:.2f} | {pr['intersections']:.3f} | "
                  f"{pr['splats']:.1f} | {pr['evaluations']:.2f} | {b['nodes']} | {b['leaves']} ({b['empty_leaves']}) | "
                  f"{b['refs_per_leaf']:.1f} | {b['seconds_total']:.1f} | {vr.get('mean_dt_over_size', float('nan')):.2e} | {vr.get('missed', '-')} |")

print()
print("## 3. Intersection settings on the default trees, zoomed view, 1 thread")
print()
print("| model | samples k | refine steps | rays/s | rays/CPU-s | F evals/ray | mean abs(dt)/radius | max | missed | normals deg |")
print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
for m in models:
    for s, r in ((4, 0), (4, 1), (4, 2), (8, 0), (8, 1)):
        j = load(f"{m}.default.zoom_samples_{s}_refine_{r}.json")
        if not j: continue
        vr = j["vs_reference"]
        print(f"| {m} | {s} | {r} | {rate(j,1):,.0f} | {rate(j,1,'rays_per_cpu_second'):,.0f} | {j['per_ray']['evaluations']:.2f} | {vr['mean_dt_over_size']:.2e} | "
              f"{vr['max_dt_over_size']:.2e} | {vr['missed']} | {vr['mean_normal_deg']:.3f} |")
EOF
echo
echo "# load average after: $(bench_load)"
