# %% [markdown]
# # A wedge of three light intensities
#
# A notebook in Jupyter's percent format (open it in JupyterLab with jupytext, in VS Code, or run
# it as a script: `python3 docs/examples/light_wedge.py out/wedge.png`). It renders the Cornell
# box with its ceiling light at three strengths, through the irradiance cache, and plots the
# three beauty images and their bounce light side by side (matplotlib from Debian).

# %%
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")  # a file, not a window: also runs on a farm node
import matplotlib.pyplot as plt
import numpy as np

import bounce

ROOT = pathlib.Path(__file__).resolve().parents[2]
SCENE = ROOT / "scenes" / "cornell" / "cornell.json"
STRENGTHS = [0.5, 1.0, 2.0]  # times the scene file's emission


def wedge(strengths=STRENGTHS, resolution=(160, 160), rays=256):
    """The scene rendered once per strength: {strength: bounce.Image}."""
    scene = bounce.Scene.load(SCENE)
    emission = np.array(scene["materials.light.emission"], dtype=float)
    images = {}
    for s in strengths:
        scene["materials.light.emission"] = (emission * s).tolist()  # any value of the scene by its path
        images[s] = scene.render(gi="cache", resolution=list(resolution), rays=rays)
    return images


def display(rgb, exposure=0.0):
    """Linear RGB to an sRGB-encoded image for the screen (a plain transfer curve)."""
    x = np.clip(rgb[..., :3] * 2.0**exposure, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)


# %%
def plot(images, path):
    fig, axes = plt.subplots(2, len(images), figsize=(3 * len(images), 6.4))
    for col, (s, img) in enumerate(images.items()):
        axes[0, col].imshow(display(img["beauty"]))
        axes[0, col].set_title(f"light x {s:g}")
        axes[1, col].imshow(display(img["indirect"], exposure=1))
        axes[1, col].set_title(f"indirect, mean {img['indirect'].mean():.3f}")
        for ax in axes[:, col]:
            ax.axis("off")
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


# %%
if __name__ == "__main__":
    out = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "out/wedge.png")
    out.parent.mkdir(parents=True, exist_ok=True)
    images = wedge()
    plot(images, out)
    for s, img in images.items():
        print(f"x{s:g}: beauty mean {img['beauty'][..., :3].mean():.4f}, {img.stats['records']:.0f} records, {img.stats['total_s']:.2f} s")
    print(f"wrote {out}")
