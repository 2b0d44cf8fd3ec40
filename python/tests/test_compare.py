"""compare(): the scores as plain data; a user's model scored with the same metric."""
import math

import numpy as np
import pytest

import osgbtf


def test_compare_gives_one_row_per_method_with_the_baseline_first(sample_btf):
    rows = osgbtf.compare(sample_btf, methods=["pca", "ptm"], holdout_fraction=0.1,
                          options={"pca": {"components": 4}})
    assert [r["method"] for r in rows] == ["lambert", "pca", "ptm"]
    assert all(isinstance(r, dict) and not r["failed"] for r in rows)
    pca = rows[1]
    assert pca["options"] == {"components": "4"}
    # The same score as fitting and measuring by hand.
    material = osgbtf.fit(sample_btf, "pca", components=4)
    assert pca["average"] == osgbtf.error(sample_btf, material)["average"]
    assert pca["bytes_per_texel"] == material.bytes_per_texel
    # Held-out directions are harder than the fitted ones, and were measured.
    for r in rows:
        assert r["held_out_pairs"] > 0
        assert math.isfinite(r["held_out_average"])
        assert 0 < r["held_out_ssim"] <= 1
    assert pca["held_out_average"] > pca["average"]
    with pytest.raises(ValueError, match="pca: option components must be"):
        osgbtf.compare(sample_btf, methods=["pca"], options={"pca": {"components": -1}})


def test_a_model_written_in_python_is_scored_like_a_method(sample_btf):
    lambert = osgbtf.fit(sample_btf, "lambert")

    def model(uv, views, lights):
        return lambert.evaluate(uv, views, lights)

    # The model that evaluates the lambert material scores what the lambert material scores.
    mine = osgbtf.error_of(sample_btf, model)
    theirs = osgbtf.error(sample_btf, lambert)
    assert mine["texels"] == theirs["texels"]
    assert mine["average"] == pytest.approx(theirs["average"], rel=1e-6)

    def constant(uv, views, lights):
        return np.full((len(uv), 3), 0.1, dtype=np.float32)

    assert osgbtf.error_of(sample_btf, constant)["average"] > theirs["average"]
    with pytest.raises(ValueError, match="must return an"):
        osgbtf.error_of(sample_btf, lambda uv, v, l: np.zeros(3))


def test_compare_writes_the_btf_compare_report_when_asked(sample_zip, tmp_path):
    btf = osgbtf.load(sample_zip)
    report = tmp_path / "report"
    rows = osgbtf.compare(btf, methods=["pca"], holdout_fraction=0,
                          options={"pca": {"components": 2}}, report=str(report))
    assert [r["method"] for r in rows] == ["lambert", "pca"]
    assert math.isnan(rows[1]["held_out_average"])
    text = (report / "report.md").read_text()
    assert "pca" in text and (report / "results.csv").exists()
    with pytest.raises(ValueError, match="report needs a BTF loaded from a file"):
        osgbtf.compare(osgbtf.sample(4), methods=["pca"], report=str(tmp_path / "r2"))
