#!/usr/bin/env python3
"""Scores your own BTF model, a Python function of (uv, view, light), with osgBTF's error metric
(Meseth et al. 2003, as `btf fit` and `btf compare` report it) next to the built-in methods.

    PYTHONPATH=build/python python3 examples/python/score_my_model.py [BTF]

The model here is a deliberately simple one: per texel the mean colour over every measured pair
times a cosine of the light, which is what the lambert baseline does too; replace `my_model` with
yours. It gets arrays of N queries: uv (N, 2) in [0, 1), view and light (N, 3) unit vectors (+Z
the surface normal), and returns (N, 3) RGB values.
"""
import sys

import numpy as np

import osgbtf


def main():
    btf = osgbtf.load(sys.argv[1]) if len(sys.argv) > 1 else osgbtf.sample(24)
    print(btf)

    # "Training": the mean over all measured pairs per texel, and the mean cosine of the lights.
    albedo = np.zeros((btf.height, btf.width, 3), dtype=np.float32)
    for v in range(len(btf.views)):
        for l in range(len(btf.lights)):
            albedo += btf.image(v, l)[::-1]  # image rows are top-down; texel y counts up
    albedo /= len(btf.views) * len(btf.lights)
    mean_cos = float(btf.lights[:, 2].mean())

    def my_model(uv, view, light):
        x = np.minimum((uv[:, 0] * btf.width).astype(int), btf.width - 1)
        y = np.minimum((uv[:, 1] * btf.height).astype(int), btf.height - 1)
        return albedo[y, x] * (np.clip(light[:, 2], 0, None) / mean_cos)[:, None]

    rows = [("my_model", 3 * 4, osgbtf.error_of(btf, my_model))]
    for result in osgbtf.compare(btf, methods=["laf", "pca"], holdout_fraction=0):
        rows.append((result["method"], result["bytes_per_texel"], result))
    print(f"{'model':10s} {'bytes/texel':>11s} {'avg error':>10s} {'RMSE':>8s} {'PSNR dB':>8s}")
    for name, size, e in sorted(rows, key=lambda r: r[2]["average"]):
        print(f"{name:10s} {size:11.1f} {e['average']:10.4f} {e['rmse']:8.4f} {e['psnr']:8.2f}")


if __name__ == "__main__":
    main()
