#!/usr/bin/env python3
"""Loads the built-in sample, fits three methods, plots their error against bytes per texel and
saves a rendered image of each (docs/python.md).

    PYTHONPATH=build/python python3 examples/python/methods_vs_size.py --out out/python
"""
import argparse
import os

import matplotlib

matplotlib.use("Agg")  # no display needed
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import osgbtf  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out/python", help="output folder")
    parser.add_argument("--size", type=int, default=32, help="texels per side of the sample")
    parser.add_argument("--methods", default="laf,pca,ptm", help="comma-separated methods")
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)

    btf = osgbtf.sample(args.size)
    print(btf)
    view, light = (45, 90), (60, 0)  # (theta, phi) in degrees
    rows = []
    renders = []
    for method in args.methods.split(","):
        material = osgbtf.fit(btf, method)
        error = osgbtf.error(btf, material)
        image, gpu_cpu = material.render(view, light)
        rows.append((method, material.bytes_per_texel, error["average"]))
        renders.append((method, image))
        print(f"{method:8s} {material.bytes_per_texel:8.1f} bytes/texel  "
              f"error {error['average']:.4f}  GPU-CPU {gpu_cpu:.2g}")
        material.save(os.path.join(args.out, f"sample-{method}.btfmat"))

    measured = btf.image(int(np.argmin(np.linalg.norm(btf.views - direction(*view), axis=1))),
                         int(np.argmin(np.linalg.norm(btf.lights - direction(*light), axis=1))))
    renders.insert(0, ("measured", measured))
    figure, (plot, *panels) = plt.subplots(
        1, 1 + len(renders), figsize=(4 + 2.2 * len(renders), 3.6),
        gridspec_kw={"width_ratios": [2.2] + [1] * len(renders)})
    for method, size, error in rows:
        plot.scatter(size, error)
        plot.annotate(method, (size, error), textcoords="offset points", xytext=(5, 5))
    plot.set_xscale("log")
    plot.set_xlabel("bytes per texel")
    plot.set_ylabel("average per-texel error")
    plot.set_title("error against size")
    for panel, (method, image) in zip(panels, renders):
        panel.imshow(np.clip(image, 0, 1) ** (1 / 2.2), interpolation="nearest")
        panel.set_title(method if method == "measured" else f"{method} (GPU)")
        panel.axis("off")
    figure.suptitle(f"the built-in sample, {args.size}x{args.size} texels; view {view}, light "
                    f"{light} (theta, phi in degrees); images gamma 2.2", fontsize=9)
    figure.tight_layout()
    picture = os.path.join(args.out, "methods-vs-size.png")
    figure.savefig(picture, dpi=100)
    print("wrote", picture)


def direction(theta, phi):
    t, p = np.radians(theta), np.radians(phi)
    return np.array([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)])


if __name__ == "__main__":
    main()
