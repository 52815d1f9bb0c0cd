"""Loading and plotting helpers shared by the notebooks: benchmark JSON in, PNG figures out.

The results folder is $TRIDIFF_RESULTS (default results/quick, relative to the repository).
A missing file or a benchmark that reported `error_occurred` (skipped: too slow, unsupported)
is reported and left out; anything else that goes wrong (a malformed file, a name that does not
parse) raises, so that a broken notebook fails its execution.
"""
import json
import os
import statistics
from dataclasses import dataclass, field
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # headless: figures go to PNG files (the notebook shows them inline too)
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

REPO = Path(__file__).resolve().parent.parent
RESULTS = Path(os.environ.get("TRIDIFF_RESULTS", "results/quick"))
if not RESULTS.is_absolute():
    RESULTS = REPO / RESULTS
FIGURES = RESULTS / "figures"
DPI = 80  # small PNGs: the README embeds some of them (docs/figures, <= 150 KB each)

# Fields of a Google Benchmark record that are not user counters.
_STANDARD = {
    "name", "family_index", "per_family_instance_index", "run_name", "run_type", "repetitions",
    "repetition_index", "threads", "iterations", "real_time", "cpu_time", "time_unit",
    "aggregate_name", "aggregate_unit", "error_occurred", "error_message", "label",
}
_SECONDS_PER_UNIT = {"ns": 1e-9, "us": 1e-6, "ms": 1e-3, "s": 1.0}

plt.rcParams.update({"figure.dpi": DPI, "savefig.dpi": DPI, "font.size": 9,
                     "axes.grid": True, "grid.alpha": 0.3})


@dataclass
class Run:
    """One benchmark: the median over its repetitions."""
    name: str                 # run name without /real_time
    parts: list               # name split at '/', without the threads:<t> and key:value parts
    keys: dict                # the key:value parts of the name (sigma, threads, ...)
    seconds: float            # wall-clock seconds per iteration
    counters: dict = field(default_factory=dict)
    repetitions: int = 1

    @property
    def threads(self):
        return int(self.keys["threads"]) if "threads" in self.keys else None


def results_file(name):
    """The path of a results file, or None (with a note) when it is not there."""
    path = RESULTS / name
    if not path.exists():
        print(f"{path}: not found, skipping what needs it")
        return None
    return path


def load_json(name):
    path = results_file(name)
    if path is None:
        return None
    with open(path) as f:
        return json.load(f)


NAME_KEYS = ("threads", "sigma")  # key:value parts of the names; shapes such as rows:4096x4096 stay parts


def split_name(run_name):
    """(parts, keys) of a benchmark name: 'BM_blur/adi/sigma:2/1024/threads:2/real_time' ->
    (['BM_blur', 'adi', '1024'], {'sigma': '2', 'threads': '2'})."""
    parts, keys = [], {}
    for part in run_name.split("/"):
        if part == "real_time":
            continue
        key, colon, value = part.partition(":")
        if colon and key in NAME_KEYS:
            keys[key] = value
        else:
            parts.append(part)
    return parts, keys


def load_benchmarks(name, verbose=True):
    """The runs of a Google Benchmark JSON file (median over repetitions of the time and of every
    counter), or None when the file is missing. Skipped runs are listed and left out."""
    data = load_json(name)
    if data is None:
        return None
    iterations, skipped = {}, {}
    for b in data["benchmarks"]:
        run_name = b.get("run_name", b["name"]).removesuffix("/real_time")
        if b.get("error_occurred"):
            skipped[run_name] = b.get("error_message", "")
        elif b["run_type"] == "iteration":
            iterations.setdefault(run_name, []).append(b)
    runs = []
    for run_name, records in iterations.items():
        parts, keys = split_name(run_name)
        unit = _SECONDS_PER_UNIT[records[0]["time_unit"]]
        counters = {}
        for key in records[0]:
            if key not in _STANDARD:
                values = [r[key] for r in records if isinstance(r.get(key), (int, float))]
                if values:
                    counters[key] = statistics.median(values)
        runs.append(Run(run_name, parts, keys,
                        statistics.median(r["real_time"] for r in records) * unit,
                        counters, len(records)))
    if verbose:
        print(f"{name}: {len(runs)} benchmarks, {len(skipped)} skipped")
        for run_name, message in sorted(skipped.items()):
            print(f"  skipped {run_name}: {message}")
    return runs


def save(fig, name):
    """Writes the figure to $TRIDIFF_RESULTS/figures/<name>.png."""
    FIGURES.mkdir(parents=True, exist_ok=True)
    path = FIGURES / f"{name}.png"
    fig.savefig(path, bbox_inches="tight")
    print(f"wrote {path}")
    return path


def nothing_to_plot(what):
    print(f"no data for {what}: skipped")


def pareto_front(times, errors):
    """Indices of the points no other point beats in both time and error, fastest first."""
    order = sorted(range(len(times)), key=lambda i: (times[i], errors[i]))
    front, best_error = [], np.inf
    for i in order:
        if errors[i] < best_error:
            front.append(i)
            best_error = errors[i]
    return front


def method_colors(methods):
    """A fixed colour per method name, the same in every panel."""
    cmap = plt.get_cmap("tab20")
    return {m: cmap(i % 20) for i, m in enumerate(sorted(methods))}


def pixels(size_text):
    """'1024' -> 1024^2, '3840x2160' -> 3840 * 2160."""
    w, _, h = size_text.partition("x")
    return int(w) * int(h or w)


def sort_sizes(sizes):
    return sorted(set(sizes), key=pixels)


def largest(values):
    return max(values, key=lambda v: pixels(v) if isinstance(v, str) else v)


def log_floor(values, floor):
    """Values for a log axis: zeros (an exact result) drawn at `floor`."""
    return np.maximum(np.asarray(values, dtype=float), floor)


# ---------------------------------------------------------------------------------------------
# Blur (bench_blur.cpp): BM_blur/<method>/sigma:<s>/<n>/threads:<t>, BM_blur_copy/<n>/threads:<t>

ERROR_FLOOR = 1e-9  # an error below float's resolution is drawn here on the log axis


def blur_table(runs):
    """One dict per blur run: method, sigma, n, threads, ms, and the counters."""
    rows = []
    for r in runs:
        if r.parts[0] == "BM_blur":
            _, method, n = r.parts
            rows.append({**r.counters, **dict(method=method, sigma=float(r.keys["sigma"]),
                                              n=n, threads=r.threads, ms=r.seconds * 1e3)})
        elif r.parts[0] == "BM_blur_copy":
            rows.append({**r.counters, **dict(method="copy", sigma=None, n=r.parts[1],
                                              threads=r.threads, ms=r.seconds * 1e3)})
        else:
            raise ValueError(f"unexpected blur benchmark {r.name}")
    return rows


def plot_time_vs_error(rows, n, threads, error="max_error"):
    """Time against error, one panel per sigma: every method a point, the Pareto frontier (no
    method both faster and more accurate) joined and filled, OpenCV a black star."""
    sigmas = sorted({r["sigma"] for r in rows if r["sigma"] is not None})
    colors = method_colors({r["method"] for r in rows})
    fig, axes = plt.subplots(1, len(sigmas), figsize=(4.2 * len(sigmas), 4), squeeze=False)
    for ax, sigma in zip(axes[0], sigmas):
        sel = [r for r in rows if r["sigma"] == sigma and r["n"] == n and r["threads"] == threads]
        times = [r["ms"] for r in sel]
        errors = list(log_floor([r[error] for r in sel], ERROR_FLOOR))
        front = set(pareto_front(times, errors))
        for i, r in enumerate(sel):
            opencv = r["method"] == "opencv"
            ax.scatter(times[i], errors[i], s=90 if opencv else 40, marker="*" if opencv else "o",
                       color="black" if opencv else colors[r["method"]],
                       edgecolors="red" if i in front else "none", linewidths=1.5, zorder=3)
            ax.annotate(r["method"], (times[i], errors[i]), fontsize=7,
                        xytext=(3, 3), textcoords="offset points")
        if front:
            idx = sorted(front, key=lambda i: times[i])
            ax.step([times[i] for i in idx], [errors[i] for i in idx], where="post",
                    color="red", alpha=0.5, label="Pareto frontier")
        ax.set(xscale="log", yscale="log", title=f"sigma {sigma:g}", xlabel="time per call (ms)")
        ax.legend(loc="best", fontsize=7)
    axes[0][0].set_ylabel(f"{error} vs exact Gaussian")
    fig.suptitle(f"Blur: time against {error}, {n}x{n} RGB float, {threads} thread(s)")
    fig.tight_layout()
    return fig


def plot_copy_ratio_bars(rows, n, threads):
    """Time in copies of the image, per method, one bar per sigma."""
    sel = [r for r in rows if r["n"] == n and r["threads"] == threads and r["sigma"] is not None]
    methods = sorted({r["method"] for r in sel})
    sigmas = sorted({r["sigma"] for r in sel})
    width = 0.8 / max(len(sigmas), 1)
    fig, ax = plt.subplots(figsize=(max(6, 0.6 * len(methods) + 2), 3.8))
    for k, sigma in enumerate(sigmas):
        by_method = {r["method"]: r["copy_ratio"] for r in sel if r["sigma"] == sigma}
        x = [i + (k - (len(sigmas) - 1) / 2) * width for i, m in enumerate(methods) if m in by_method]
        ax.bar(x, [by_method[m] for m in methods if m in by_method], width, label=f"sigma {sigma:g}")
    ax.axhline(1, color="black", lw=1, ls="--", label="copy")
    ax.set_xticks(range(len(methods)), methods, rotation=45, ha="right")
    ax.set(yscale="log", ylabel="time / copy time", title=f"Blur cost in copies, {n}x{n}, {threads} thread(s)")
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    return fig


def plot_effective_sigma(table):
    """table["rows"]: {method, sigma, effective_sigma[, seed001_sigma]}: the sigma a method
    achieves (seed 001 §4.1.2) against the one asked for, beside the seed's own where given."""
    fig, ax = plt.subplots(figsize=(5.5, 4))
    rows = table["rows"]
    colors = method_colors({r["method"] for r in rows})
    for m in sorted(colors):
        pts = sorted((r["sigma"], r["effective_sigma"], r.get("seed001_sigma")) for r in rows if r["method"] == m)
        ax.plot([p[0] for p in pts], [p[1] / p[0] for p in pts], "o-", color=colors[m], label=m)
        seed = [(p[0], p[2] / p[0]) for p in pts if p[2] is not None]
        if seed:
            ax.plot(*zip(*seed), "x", color=colors[m])
    ax.axhline(1, color="black", lw=1)
    ax.set(xscale="log", xlabel="sigma asked for", ylabel="effective sigma / sigma",
           title="Effective sigma" + (" (x: seed 001 tables)" if any(
               r.get("seed001_sigma") is not None for r in rows) else ""))
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    return fig


def plot_pyramid_levels(table):
    """table["levels"]: {filter, levels, effective_sigma, seed001_sigma}: the effective sigma of
    each pyramid level measured here (dots) against seed 001's Tables A.1-A.3 (crosses)."""
    fig, ax = plt.subplots(figsize=(5.5, 4))
    rows = table.get("levels", [])
    colors = method_colors({r["filter"] for r in rows})
    for f in sorted(colors):
        pts = sorted((r["levels"], r["effective_sigma"], r["seed001_sigma"])
                     for r in rows if r["filter"] == f)
        ax.plot([p[0] for p in pts], [p[1] for p in pts], "o-", color=colors[f],
                label=f"{f} (here)")
        ax.plot([p[0] for p in pts], [p[2] for p in pts], "x", color=colors[f], ms=9,
                label=f"{f} (seed 001)")
    ax.set(yscale="log", xlabel="pyramid levels", ylabel="effective sigma (px)",
           title="Pyramid levels: effective sigma against seed 001 Tables A.1-A.3")
    ax.set_xticks(sorted({r["levels"] for r in rows}))
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    return fig


# ---------------------------------------------------------------------------------------------
# Solvers (bench_solvers.cpp): BM_solvers_<method>/<scalar>/<form>/<layout>:<systems>x<n>/threads:<t>

def solver_table(runs):
    rows = []
    for r in runs:
        method = r.parts[0].removeprefix("BM_solvers_")
        if method.startswith("stream_"):
            _, scalar, array = r.parts
            rows.append(dict(method=method, scalar=scalar, form="", layout="array", systems=1,
                             n=int(array.partition(":")[2]), threads=r.threads,
                             seconds=r.seconds, **r.counters))
            continue
        _, scalar, form, shape = r.parts
        layout, _, dims = shape.partition(":")
        systems, _, n = dims.partition("x")
        rows.append(dict(method=method, scalar=scalar, form=form, layout=layout,
                         systems=int(systems), n=int(n), shape=shape, threads=r.threads,
                         seconds=r.seconds, **r.counters))
    return rows


def stream_lines(rows, threads):
    """The STREAM triad and copy bandwidths at a thread count (best seen), bytes/s."""
    triad = max([r.get("triad_bytes_per_second", 0) for r in rows if r["threads"] == threads] +
                [r["bytes_per_second"] for r in rows
                 if r["method"] == "stream_triad" and r["threads"] == threads], default=0)
    copy = max([r["bytes_per_second"] for r in rows
                if r["method"] == "stream_copy" and r["threads"] == threads], default=0)
    return triad, copy


def plot_bandwidth(rows, scalar, threads):
    """Bytes per second each method must move at least, per shape, one panel per form."""
    sel = [r for r in rows if r["scalar"] == scalar and r["threads"] == threads and r["form"]]
    forms = sorted({r["form"] for r in sel})
    colors = method_colors({r["method"] for r in rows})
    triad, copy = stream_lines(rows, threads)
    fig, axes = plt.subplots(1, len(forms), figsize=(5 * len(forms), 4), squeeze=False, sharey=True)
    for ax, form in zip(axes[0], forms):
        f = [r for r in sel if r["form"] == form]
        shapes = sorted({r["shape"] for r in f}, key=lambda s: (s.split(":")[0], s))
        methods = sorted({r["method"] for r in f})
        width = 0.8 / len(methods)
        for k, m in enumerate(methods):
            by_shape = {r["shape"]: r["bytes_per_second"] / 1e9 for r in f if r["method"] == m}
            x = [i + (k - (len(methods) - 1) / 2) * width for i, s in enumerate(shapes) if s in by_shape]
            ax.bar(x, [by_shape[s] for s in shapes if s in by_shape], width, label=m, color=colors[m])
        if triad:
            ax.axhline(triad / 1e9, color="black", ls="--", lw=1, label="STREAM triad")
        if copy:
            ax.axhline(copy / 1e9, color="gray", ls=":", lw=1, label="STREAM copy")
        ax.set_xticks(range(len(shapes)), shapes, rotation=20, ha="right")
        ax.set(title=f"{form}", ylabel="GB/s (arrays moved once)")
        ax.legend(fontsize=7, ncol=2)
    fig.suptitle(f"Solvers: bandwidth, {scalar}, {threads} thread(s)")
    fig.tight_layout()
    return fig


def plot_time_per_row(rows, scalar, threads):
    """Time per system (an image row) against its length n, one panel per form."""
    sel = [r for r in rows if r["scalar"] == scalar and r["threads"] == threads and r["form"]
           and r["layout"] in ("rows", "single")]
    forms = sorted({r["form"] for r in sel})
    colors = method_colors({r["method"] for r in rows})
    fig, axes = plt.subplots(1, len(forms), figsize=(4.5 * len(forms), 3.8), squeeze=False, sharey=True)
    for ax, form in zip(axes[0], forms):
        for m in sorted({r["method"] for r in sel if r["form"] == form}):
            pts = sorted((r["n"], r["seconds"] / r["systems"]) for r in sel
                         if r["form"] == form and r["method"] == m)
            ax.plot([p[0] for p in pts], [p[1] * 1e6 for p in pts], "o-", label=m, color=colors[m])
        ax.set(xscale="log", yscale="log", xlabel="n (unknowns per system)", title=form)
        ax.legend(fontsize=7)
    axes[0][0].set_ylabel("time per row (us)")
    fig.suptitle(f"Solvers: time per row against n, {scalar}, {threads} thread(s)")
    fig.tight_layout()
    return fig


def stability_matrix(table):
    """(row labels, column labels, worst ratio array, text array) of the stability table: per
    class and precision, per method (and thread count), the worst max(forward, backward) ratio
    to LAPACK over the sizes; where tridiff did not solve, its outcome instead."""
    def column(r):
        return r["method"] + (f" x{r['threads']}" if r["threads"] > 1 else "")
    columns = list(dict.fromkeys(column(r) for r in table["rows"]))
    labels = list(dict.fromkeys((r["class"], r["precision"]) for r in table["rows"]))
    ratio = np.full((len(labels), len(columns)), np.nan)
    text = np.full(ratio.shape, "", dtype=object)
    for r in table["rows"]:
        i, j = labels.index((r["class"], r["precision"])), columns.index(column(r))
        ratios = [x for x in (r["forward_ratio"], r["backward_ratio"]) if x is not None]
        if ratios:
            ratio[i, j] = np.fmax(ratio[i, j], max(ratios))
        if r["outcome"] != "solved" and r["outcome"] not in text[i, j]:
            text[i, j] = (text[i, j] + " " + r["outcome"]).strip()
        elif r["lapack_outcome"] != "solved" and "L:" not in text[i, j]:
            text[i, j] = (text[i, j] + " L:" + r["lapack_outcome"]).strip()
    return [f"{c} {p}" for c, p in labels], columns, ratio, text


def plot_stability(table):
    from matplotlib.colors import LogNorm
    rows, columns, ratio, text = stability_matrix(table)
    fig, ax = plt.subplots(figsize=(1.0 * len(columns) + 3, 0.32 * len(rows) + 1.5))
    cmap = plt.get_cmap("RdYlGn_r").copy()
    cmap.set_bad("lightgray")
    image = ax.imshow(np.clip(ratio, 0.1, 100), cmap=cmap, norm=LogNorm(0.1, 100), aspect="auto")
    for (i, j), value in np.ndenumerate(ratio):
        label = text[i, j] if text[i, j] and not np.isfinite(value) else (
            f"{value:.2g}" + ("*" if text[i, j] else "") if np.isfinite(value) else "")
        ax.text(j, i, label, ha="center", va="center", fontsize=6.5)
    ax.set_xticks(range(len(columns)), columns, rotation=30, ha="right")
    ax.set_yticks(range(len(rows)), rows, fontsize=7)
    ax.grid(False)
    fig.colorbar(image, ax=ax, label="worst error / LAPACK's (floored at eps)")
    ax.set_title("Stability: error ratio to LAPACK ?gtsv, worst over n = "
                 + ", ".join(str(n) for n in table["sizes"])
                 + "\n(* some sizes not solved by tridiff or LAPACK; grey: never solved)", fontsize=8)
    fig.tight_layout()
    return fig


# ---------------------------------------------------------------------------------------------
# Depth of field (bench_dof.cpp): BM_dof_<method>/<W>x<H>/threads:<t> (the procedural scene),
# BM_dof_<method>/<scene>/<W>x<H>/threads:<t>, BM_dof_<method>_focus/<percent>/threads:<t>

def dof_table(runs):
    rows = []
    for r in runs:
        head, rest = r.parts[0], r.parts[1:]
        if not head.startswith("BM_dof_"):
            raise ValueError(f"unexpected DOF benchmark {r.name}")
        method = head.removeprefix("BM_dof_")
        if method.endswith("_focus"):
            rows.append(dict(kind="focus", method=method.removesuffix("_focus"),
                             percent=int(rest[0]), size="2048x2048", threads=r.threads,
                             ms=r.seconds * 1e3, **r.counters))
        else:
            scene, size = (rest[0], rest[1]) if len(rest) == 2 else ("procedural", rest[0])
            rows.append(dict(kind="method", method=method, scene=scene, size=size,
                             threads=r.threads, ms=r.seconds * 1e3, **r.counters))
    return rows


def plot_focus_fraction(rows):
    """Each method's cost against the out-of-focus fraction of the frame (in-focus tiles are
    skipped), one line per method and thread count."""
    sel = [r for r in rows if r["kind"] == "focus"]
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(9, 3.6))
    colors = method_colors({r["method"] for r in sel})
    for m in sorted({r["method"] for r in sel}):
        for t in sorted({r["threads"] for r in sel if r["method"] == m}):
            pts = sorted((r["percent"], r["ms"], r["copy_ratio"]) for r in sel
                         if r["threads"] == t and r["method"] == m)
            label = f"{m}, {t} thread(s)"
            ax.plot([p[0] for p in pts], [p[1] for p in pts], "o-", label=label, color=colors[m])
            ax2.plot([p[0] for p in pts], [p[2] for p in pts], "o-", label=label, color=colors[m])
    ax.set(xlabel="out of focus (% of the frame)", ylabel="time (ms)", title="2048x2048",
           yscale="log")
    ax2.set(xlabel="out of focus (% of the frame)", ylabel="time / copy time", title="in copies",
            yscale="log")
    ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def plot_method_times(rows):
    """Time per method and image size on the procedural scene, one panel per thread count, the
    copy beside them."""
    sel = [r for r in rows if r["kind"] == "method" and r["scene"] == "procedural"]
    threads = sorted({r["threads"] for r in sel})
    methods = sorted({r["method"] for r in sel}, key=lambda m: (m != "copy", m))
    sizes = sort_sizes(r["size"] for r in sel)
    colors = method_colors(methods)
    width = 0.8 / len(methods)
    fig, axes = plt.subplots(1, len(threads), figsize=(4.5 * len(threads), 3.8), squeeze=False, sharey=True)
    for ax, t in zip(axes[0], threads):
        for k, m in enumerate(methods):
            by_size = {r["size"]: r["ms"] for r in sel if r["method"] == m and r["threads"] == t}
            x = [i + (k - (len(methods) - 1) / 2) * width for i, s in enumerate(sizes) if s in by_size]
            ax.bar(x, [by_size[s] for s in sizes if s in by_size], width, label=m, color=colors[m])
        ax.set_xticks(range(len(sizes)), sizes)
        ax.set(yscale="log", title=f"{t} thread(s)", xlabel="image size (RGB float)")
        ax.legend(fontsize=7)
    axes[0][0].set_ylabel("time (ms), CoC given")
    fig.suptitle("Depth of field: time per method and size, built-in scene")
    fig.tight_layout()
    return fig


def plot_dof_error_vs_time(rows, size="1024x1024"):
    """RMSE against the scatter reference (linear RGB, the 1024^2 scene) against time, per
    thread count; the reference itself is left out (its error is 0)."""
    sel = [r for r in rows if r["kind"] == "method" and r["size"] == size
           and r["scene"] == "procedural" and "rmse_vs_scatter" in r and r["method"] != "scatter"]
    threads = sorted({r["threads"] for r in sel})
    colors = method_colors({r["method"] for r in sel})
    fig, axes = plt.subplots(1, len(threads), figsize=(4.5 * len(threads), 3.6), squeeze=False)
    for ax, t in zip(axes[0], threads):
        for r in sel:
            if r["threads"] != t:
                continue
            ax.plot(r["ms"], r["rmse_vs_scatter"], "o", color=colors[r["method"]])
            ax.annotate(r["method"], (r["ms"], r["rmse_vs_scatter"]), fontsize=7,
                        xytext=(3, 3), textcoords="offset points")
        ax.set(xscale="log", yscale="log", xlabel=f"time per frame (ms), {size}",
               ylabel="RMSE against scatter (linear RGB)", title=f"{t} thread(s)")
    fig.suptitle("Depth of field: error against time, built-in scene")
    fig.tight_layout()
    return fig


def plot_dof_scenes(rows, size="1024x1024", threads=2, score="psnr_vs_scatter",
                    reference="scatter"):
    """A PSNR (`score`: against the scatter reference, or against the thin-lens truth) against
    time, one panel per built-in scene that has it, every method a point, the Pareto frontier
    (no method both faster and more accurate) joined. The `reference` method itself is left out
    (its PSNR against itself is infinite)."""
    sel = [r for r in rows if r["kind"] == "method" and r["size"] == size
           and r["threads"] == threads and r["method"] != reference
           and np.isfinite(r.get(score, np.nan))]
    scenes = sorted({r["scene"] for r in sel})
    colors = method_colors({r["method"] for r in sel})
    columns = min(3, len(scenes))
    fig, axes = plt.subplots(-(-len(scenes) // columns), columns, figsize=(4.2 * columns,
                             3.2 * -(-len(scenes) // columns)), squeeze=False)
    for ax in axes.flat[len(scenes):]:
        ax.axis("off")
    against = score.removeprefix("psnr_vs_")
    for ax, scene in zip(axes.flat, scenes):
        pts = sorted((r["ms"], r[score], r["method"]) for r in sel if r["scene"] == scene)
        for ms, psnr, m in pts:
            ax.plot(ms, psnr, "o", color=colors[m])
            ax.annotate(m, (ms, psnr), fontsize=6, xytext=(3, 2), textcoords="offset points")
        frontier, best = [], -np.inf
        for ms, psnr, _ in pts:  # by time: a point is on the frontier if it beats all faster
            if psnr > best:
                frontier.append((ms, psnr))
                best = psnr
        ax.plot(*zip(*frontier), "-", color="black", lw=0.8)
        ax.set(xscale="log", title=scene, xlabel="time (ms)", ylabel=f"PSNR vs {against} (dB)")
    fig.suptitle(f"Depth of field per scene: error against {against} and time "
                 f"({size}, {threads} threads)")
    fig.tight_layout()
    return fig


def read_png(path):
    return plt.imread(str(path))[..., :3]


def plot_image_grid(folder, columns=4):
    """Input, CoC and each method's output (from `tridiff dof`), then each method's absolute
    difference (x4) to the scatter reference (to adi when there is no reference)."""
    reports = {json.loads(p.read_text())["method"]: p for p in sorted(folder.glob("*.json"))}
    reference = "scatter" if "scatter" in reports else "adi"
    methods = sorted(reports, key=lambda m: (m != reference, m))
    images = {m: read_png(folder / f"{m}.png") for m in methods}
    panels = [("input", read_png(folder / "input.png")),
              ("CoC (red far, blue near)", read_png(folder / "coc.png"))]
    panels += [(m, images[m]) for m in methods]
    if reference in images:
        panels += [(f"|{m} - {reference}| x4",
                    np.clip(4 * np.abs(images[m] - images[reference]), 0, 1))
                   for m in methods if m != reference]
    rows = -(-len(panels) // columns)
    fig, axes = plt.subplots(rows, columns, figsize=(2.0 * columns, 1.3 * rows), squeeze=False)
    for ax in axes.flat:
        ax.axis("off")
    for ax, (title, image) in zip(axes.flat, panels):
        ax.imshow(image)
        ax.set_title(title, fontsize=8)
    fig.tight_layout()
    return fig


# ---------------------------------------------------------------------------------------------
# Scaling: any benchmark with an image size and a thread count

def plot_cost_vs_size(series, title):
    """series: {(method, threads): [(pixels, seconds), ...]} -> ns per pixel against pixels."""
    fig, ax = plt.subplots(figsize=(5.5, 3.8))
    colors = method_colors({m for m, _ in series})
    for (m, t), pts in sorted(series.items()):
        pts = sorted(pts)
        ax.plot([p[0] for p in pts], [p[1] / p[0] * 1e9 for p in pts], "o-" if t == 1 else "s--",
                color=colors[m], label=f"{m}, {t} thr")
    ax.set(xscale="log", yscale="log", xlabel="pixels", ylabel="ns per pixel", title=title)
    ax.legend(fontsize=6, ncol=2)
    fig.tight_layout()
    return fig


def plot_speedup(groups, title):
    """groups: {label: {threads: seconds}} -> bars of the speed-up over 1 thread."""
    labels = sorted(g for g, by_t in groups.items() if 1 in by_t and len(by_t) > 1)
    fig, ax = plt.subplots(figsize=(max(5, 0.3 * len(labels) + 2), 3.8))
    ax.bar(range(len(labels)), [groups[g][1] / groups[g][max(groups[g])] for g in labels])
    ax.axhline(1, color="black", lw=1)
    most = max((max(groups[g]) for g in labels), default=1)
    ax.axhline(most, color="gray", ls="--", lw=1, label=f"{most} threads: ideal")
    ax.legend(fontsize=7)
    ax.set_xticks(range(len(labels)), labels, rotation=60, ha="right", fontsize=7)
    ax.set(ylabel="speed-up, most threads vs 1", title=title)
    fig.tight_layout()
    return fig
