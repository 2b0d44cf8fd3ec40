"""Materials: evaluate, images, save and open, rendering; compared with the btf tool."""
import numpy as np
import pytest

import osgbtf
from conftest import SIZE, run_btf
from exr import read_rgb


def texel_centres(width, height):
    """uv of every texel centre, in the order of an image with rows top-down."""
    x = (np.arange(width) + 0.5) / width
    y = (np.arange(height)[::-1] + 0.5) / height  # row 0 is the top: texel y = height - 1
    u, v = np.meshgrid(x, y)
    return np.stack([u.ravel(), v.ravel()], axis=1).astype(np.float32)


def test_evaluate_at_every_texel_is_the_cpu_image_bit_for_bit(pca, sample_btf):
    for vi, li in [(0, 0), (30, 61), (80, 7)]:
        v, l = sample_btf.views[vi], sample_btf.lights[li]
        image = pca.image(v, l)
        assert image.shape == (SIZE, SIZE, 3) and image.dtype == np.float32
        values = pca.evaluate(texel_centres(SIZE, SIZE), v, l)
        assert np.array_equal(values.reshape(SIZE, SIZE, 3), image)
        # (theta, phi) in degrees names the same direction, computed the same way.
        assert np.array_equal(pca.image(sample_btf.view_angles[vi], sample_btf.light_angles[li]),
                              image)


def test_evaluate_is_vectorised_and_broadcasts(pca, sample_btf):
    n = 50
    rng = np.random.default_rng(1)
    uv = rng.random((n, 2), dtype=np.float32)
    views = sample_btf.views[rng.integers(0, 81, n)]
    lights = sample_btf.lights[rng.integers(0, 81, n)]
    out = pca.evaluate(uv, views, lights)
    assert out.shape == (n, 3) and out.dtype == np.float32
    one_by_one = np.concatenate([pca.evaluate(uv[i], views[i], lights[i]) for i in range(n)])
    assert np.array_equal(out, one_by_one)
    # At measured directions and texel centres the model is close to the measured values.
    x = (uv[:, 0] * SIZE).astype(int)
    y = (uv[:, 1] * SIZE).astype(int)
    vi = [int(np.argmin(np.linalg.norm(sample_btf.views - v, axis=1))) for v in views]
    li = [int(np.argmin(np.linalg.norm(sample_btf.lights - l, axis=1))) for l in lights]
    measured = np.array([sample_btf.image(a, b)[SIZE - 1 - y[i], x[i]]
                         for i, (a, b) in enumerate(zip(vi, li))])
    assert np.abs(out - measured).mean() < 0.03
    with pytest.raises(ValueError, match="same N"):
        pca.evaluate(uv, views[:3], lights)
    with pytest.raises(ValueError, match=r"shape \(N, 3\)"):
        pca.evaluate(uv, views[:, :2], lights)
    # float64 input is converted once; the result is the same as from float32.
    assert np.array_equal(pca.evaluate(uv.astype(np.float64), views, lights), out)


def test_image_equals_btf_eval_cpu_exactly(pca, data_dir, btf_tool):
    path = data_dir / "pca.btfmat"
    pca.save(str(path))
    out = data_dir / "cpu.exr"
    run_btf(btf_tool, "eval", path, "--view", "45,90", "--light", "60,0", "--cpu", "-o", out)
    expected = read_rgb(out)
    opened = osgbtf.open_material(str(path))
    assert opened.method == "pca" and opened.options == pca.options
    assert np.array_equal(opened.image((45, 90), (60, 0)), expected)
    # The material in memory and the one saved and opened again are the same model.
    assert np.array_equal(pca.image((45, 90), (60, 0)), expected)


def test_open_material_reads_a_ubo2014_file_as_fmf(ubo2014_file):
    material = osgbtf.open_material(ubo2014_file)
    assert material.method == "fmf"
    assert material.image((30, 0), (45, 90)).max() > 0


def test_save_errors(pca, tmp_path):
    with pytest.raises(osgbtf.Error, match="no-such-folder"):
        pca.save(str(tmp_path / "no-such-folder" / "x.btfmat"))
    with pytest.raises(osgbtf.Error, match="no such file"):
        osgbtf.open_material(str(tmp_path / "missing.btfmat"))
    with pytest.raises(ValueError, match="theta"):
        pca.image((95, 0), (0, 0))


def test_render_equals_btf_eval(pca, data_dir, btf_tool):
    path = data_dir / "pca-render.btfmat"
    pca.save(str(path))
    out = data_dir / "gpu.exr"
    run_btf(btf_tool, "eval", path, "--view", "30,0", "--light", "45,90", "-o", out)
    expected = read_rgb(out)
    image, difference = osgbtf.open_material(str(path)).render((30, 0), (45, 90))
    assert image.shape == expected.shape
    # The same shader on the same renderer: the same pixels; and close to the CPU image.
    assert np.array_equal(image, expected)
    assert difference < 2e-3
    cpu = pca.image((30, 0), (45, 90))
    assert np.abs(image - cpu).max() == pytest.approx(difference, abs=1e-7)


def test_a_mip_mapped_material_evaluates_its_base_level(sample_btf):
    m = osgbtf.fit(sample_btf, "pca", components=4, mipmap=True)
    assert m.mip_levels == 5  # 16, 8, 4, 2, 1
    assert (m.width, m.height) == (SIZE, SIZE)
    v, l = sample_btf.views[12], sample_btf.lights[50]
    image = m.image(v, l)
    assert image.shape == (SIZE, SIZE, 3)
    assert np.array_equal(m.evaluate(texel_centres(SIZE, SIZE), v, l).reshape(image.shape), image)
    # Scored against every level's data, as `btf fit --mipmap` scores it.
    assert osgbtf.error(sample_btf, m)["texels"] > SIZE * SIZE


def test_render_at_another_size_filters_like_the_cpu_reference(pca, sample_btf):
    v, l = sample_btf.view_angles[5], sample_btf.light_angles[30]
    image, difference = pca.render(v, l)
    # The patch drawn into as many pixels as texels is btf eval's image.
    same, _ = pca.render(v, l, size=SIZE)
    assert np.array_equal(same, image)
    big, difference = pca.render(v, l, size=(3 * SIZE, 2 * SIZE))
    assert big.shape == (2 * SIZE, 3 * SIZE, 3)
    # Magnified: the hardware's bilinear filter against evaluateFiltered (GL's filter weights
    # have a few bits less than float).
    assert difference < 0.01
    assert np.abs(big).max() > 0.05
    with pytest.raises(ValueError, match="size must be"):
        pca.render(v, l, size=0)
