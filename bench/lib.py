"""What the bench scripts share: the binary, the scenes, running bounce, the error of an image
against a reference (and the reference's own noise), equal-error reading of time-error
curves, and the log-log plot. Imported by bench/run, bench/parallel and bench/sponza-floor."""
import json, math, os, re, subprocess, sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BIN = os.environ.get("BOUNCE_BIN", os.path.join(ROOT, "build", "bounce"))
MICRO = os.path.join(os.path.dirname(BIN), "bounce_micro")
SCENES = {
    "cornell": os.path.join(ROOT, "scenes", "cornell", "cornell.json"),
    "sponza": os.path.join(ROOT, "bench", "scenes", "sponza.json"),
    "sibenik": os.path.join(ROOT, "bench", "scenes", "sibenik.json"),
    "bunny": os.path.join(ROOT, "bench", "scenes", "bunny.json"),
    "ogre": os.path.join(ROOT, "bench", "scenes", "ogre.json"),
    "furball": os.path.join(ROOT, "scenes", "fur", "furball.json"),
    "grass": os.path.join(ROOT, "scenes", "fur", "grass.json"),
    "foliage": os.path.join(ROOT, "scenes", "foliage", "foliage.json"),
}


def commit():
    """The short hash of the checked-out commit (for reports)."""
    return subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()


def timed_render(scene, deep, out, res, threads, extra):
    """Renders from `deep` with the scene's radiosity textures (baked once beside the deep file,
    reused as lighters do); returns (time of radiosity load + gather + shading, stats)."""
    stats = out.replace(".exr", ".json")
    textures = deep.replace(".deep.exr", ".radiosity")
    run(["render", scene, "-o", out, "--deep-in", deep, "--res", res, "--threads", str(threads), "-q", "--stats-json", stats,
         "--radiosity-textures", textures] + BAKE + extra)
    s = json.load(open(stats))
    ph = s["phases_s"]
    return sum(ph.get(k, 0.0) for k in ("radiosity load", "gather", "shading")), s


# Every bench render of a scene shades gather hits from the same radiosity textures (#15: same
# deep buffer and textures per scene), baked once at this quality: the references in out/bench
# were made with them. (The default, auto = the scene's light_samples, would re-bake whenever
# a scene's light_samples differ and put that bake's noise into the measured error.)
BAKE = ["--radiosity-light-samples", "16"]


def reference_rays(folder, tag):
    """Rays of the reference bench/run keeps for `tag` in `folder` (the one with the most), or None."""
    refs = [int(m.group(1)) for f in os.listdir(folder) for m in [re.fullmatch(re.escape(tag) + r"\.ref(\d+)\.exr", f)] if m]
    return max(refs) if refs else None


def run(args):
    r = subprocess.run([BIN] + args, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"bench: bounce {' '.join(args)} failed:\n{r.stderr}")
    return r.stdout


def error(test, ref, layer, diff=True):
    """Relative RMSE of `layer` of `test` against `ref` (and a diff image beside `test`)."""
    j = json.loads(run(["compare", test, ref, "--layer", layer, "--json"] +
                       (["--diff", test.replace(".exr", ".diff.png")] if diff else [])))
    return j[layer]["rel_rmse"]


def reference_noise(brute, ref_rays):
    """Relative RMSE of the reference itself, from the brute-force rows (rays, measured error):
    the least-squares fit of measured^2 = b (N^-2g + N_ref^-2g) in log space."""
    if len(brute) < 2:
        return 0.0
    best = None
    for i in range(40, 121):
        g = i / 100
        terms = [n ** (-2 * g) + ref_rays ** (-2 * g) for n, _ in brute]
        logb = sum(math.log(e * e / t) for (_, e), t in zip(brute, terms)) / len(brute)
        res = sum((math.log(e * e / t) - logb) ** 2 for (_, e), t in zip(brute, terms))
        if best is None or res < best[0]:
            best = (res, g, math.exp(logb))
    _, g, b = best
    return math.sqrt(b * ref_rays ** (-2 * g))


def corrected(err, ref_err):
    """The error against the truth: the reference's noise removed in quadrature (floored at a
    tenth of the measured error so a row at the reference's own level stays visible)."""
    return math.sqrt(max(err * err - ref_err * ref_err, 0.01 * err * err))


def loglog_time_at(points, err):
    """Time at error `err` on a curve of (time, error) points, interpolated in log-log. Only
    segments where the lower error took longer count: a noisy series whose error rises with
    time (Hessian radii shrinking with more rays) says nothing about the time at an error, and
    extrapolating along it gave absurd speed-ups."""
    pts = sorted(points, key=lambda p: p[1])  # by error
    ok = lambda a, b: b[1] > a[1] and a[0] > b[0]
    for (t0, e0), (t1, e1) in zip(pts, pts[1:]):
        if e0 <= err <= e1 and ok((t0, e0), (t1, e1)):
            f = (math.log(err) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(t0) + f * (math.log(t1) - math.log(t0)))
    # Just outside the curve (within 25 % of its error range): extrapolate along its nearest
    # segment, and say so. Farther out a stalling curve would promise what it never reaches.
    if len(pts) >= 2 and (0.8 * pts[0][1] <= err < pts[0][1] or pts[-1][1] < err <= 1.25 * pts[-1][1]):
        (t0, e0), (t1, e1) = (pts[0], pts[1]) if err < pts[0][1] else (pts[-2], pts[-1])
        if ok((t0, e0), (t1, e1)):
            slope = (math.log(t1) - math.log(t0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(t0) + slope * (math.log(err) - math.log(e0))), "extrapolated"
    return None


def plot(folder, tag, brute, series):
    """Log-log time-error curves of both methods (the picture users look at first)."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("bench: no matplotlib (apt install python3-matplotlib): skipping the plot", file=sys.stderr)
        return
    os.makedirs(folder, exist_ok=True)
    fig, ax = plt.subplots(figsize=(5.5, 4), dpi=110)
    curves = [(brute, "brute force (every pixel)", "o-")] + [(c, f"cache, {label}", "s-") for label, c in series]
    for pts, label, style in curves:
        pts = sorted(pts)
        ax.plot([p[0] for p in pts], [100 * p[1] for p in pts], style, label=label)
    for e in (2, 1, 0.5):
        ax.axhline(e, color="grey", lw=0.5, ls=":")
    ax.set_xscale("log")
    ax.set_yscale("log")
    from matplotlib.ticker import FormatStrFormatter, NullFormatter
    ax.set_yticks([t for t in (0.25, 0.5, 1, 2, 4, 8, 16) if t >= 0.5 * 100 * min(p[1] for c, _, _ in curves for p in c)
                   and t <= 2 * 100 * max(p[1] for c, _, _ in curves for p in c)])
    ax.yaxis.set_major_formatter(FormatStrFormatter("%g"))
    ax.yaxis.set_minor_formatter(NullFormatter())
    lo = min(p[0] for c, _, _ in curves for p in c)
    hi = max(p[0] for c, _, _ in curves for p in c)
    ax.set_xticks([t for t in (0.5, 1, 2, 5, 10, 20, 50, 100, 200, 500, 1000, 2000) if 0.7 * lo <= t <= 1.4 * hi])
    ax.xaxis.set_major_formatter(FormatStrFormatter("%g"))
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("time, 1 thread (s)")
    ax.set_ylabel("relative RMSE, reference noise removed (%)")
    ax.set_title(tag)
    ax.legend()
    ax.grid(True, which="both", lw=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(folder, f"bench-{tag}.png"))
    plt.close(fig)
