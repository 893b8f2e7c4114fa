"""Tests of the Python package `mesorve` (run by scripts/test-python)."""

import csv
import os
import pathlib
import subprocess

import numpy as np
import pytest

import mesorve

ROOT = pathlib.Path(__file__).resolve().parents[2]
RVE = os.environ.get("MESORVE_RVE_BIN", str(ROOT / "target" / "release" / "rve"))
IMPLEX = str(ROOT / "scenes" / "paper_rve_host_implex.toml")


@pytest.fixture(scope="module")
def paper():
    return mesorve.Model()


def along(n, scale):
    """n strains along [1, -0.2, 0.05], point k at (k + 1) / n of `scale`."""
    return np.outer(scale * np.arange(1, n + 1) / n, [1.0, -0.2, 0.05])


def test_shapes_and_report(paper):
    points = paper.points(3)
    assert len(points) == 3
    sig, D = points.update(along(3, 1e-4))
    assert sig.shape == (3, 3) and D.shape == (3, 3, 3)
    assert np.all(sig[:, 0] > 0) and np.all(np.diff(sig[:, 0]) > 0)
    report = points.report()
    for key in ("iterations", "substeps", "factorizations", "reliability",
                "suggested_step_ratio", "s_zz", "fast", "shared_from", "error_estimate"):
        assert report[key].shape == (3,), key
    assert np.all(report["reliability"] == 1) and np.all(report["substeps"] >= 1)
    assert np.all(report["shared_from"] == -1) and np.all(report["error_estimate"] == 0)
    sig2, none = points.update(along(3, 1e-4), tangent="none")
    assert none is None and np.array_equal(sig, sig2)
    # integer input is converted; a wrong shape is a ValueError
    points.update(np.zeros((3, 3), dtype=int))
    with pytest.raises(ValueError):
        points.update(np.zeros((2, 3)))
    with pytest.raises(ValueError):
        points.update(np.zeros((3, 3)), tangent="secant")


def test_errors_carry_message_and_index(paper):
    points = paper.points(4)
    eps = along(4, 1e-4)
    eps[2, 1] = np.nan
    with pytest.raises(mesorve.RveError) as info:
        points.update(eps)
    assert info.value.index == 2 and info.value.indices == [2]
    assert "not finite" in info.value.message and "point 2" in str(info.value)
    assert list(points.report()["reliability"]) == [1, 1, 0, 1]
    with pytest.raises(mesorve.RveError) as info:
        points.commit()  # point 2 has no trial
    assert info.value.index == 2 and "no trial" in info.value.message
    eps[2, 1] = 0.5  # absurd: |component| > 0.1
    with pytest.raises(mesorve.RveError, match="point 2"):
        points.update(eps)
    with pytest.raises(mesorve.RveError, match="dtime"):
        points.update(along(4, 1e-4), dtime=float("inf"))
    with pytest.raises(mesorve.RveError):
        mesorve.Model(str(ROOT / "scenes" / "no_such_scene.toml"))
    with pytest.raises(mesorve.RveError, match="scene"):
        mesorve.Model(text="[materials]\nnonsense = 1\n")


def test_commit_and_revert(paper):
    points = paper.points(2)
    eps = along(2, 3e-4)  # past the peak: damage
    sig_a, _ = points.update(eps)
    points.revert()
    sig_b, _ = points.update(eps)
    assert np.array_equal(sig_a, sig_b), "revert keeps the committed state"
    points.commit()
    sig_c, _ = points.update(np.zeros((2, 3)))  # back to zero strain: secant unloading
    assert np.allclose(sig_c, 0.0, atol=1e-12)
    fresh = paper.points(2)
    sig_d, D_d = fresh.update(eps / 2)
    sig_e, D_e = points.update(eps / 2)
    assert sig_e[1, 0] < sig_d[1, 0], "the damaged point is softer than a virgin one"
    points.reset()
    sig_f, _ = points.update(eps / 2)
    assert np.array_equal(sig_f, sig_d)


def test_state_bytes_round_trip(paper):
    points = paper.points(3)
    points.update(along(3, 3e-4))
    points.commit()
    whole = points.to_bytes()
    one = points.state(1)
    other = paper.points(3)
    other.load_bytes(whole)
    third = paper.points(3)
    third.load_state(1, one)
    eps = along(3, 1e-4)
    sig, D = points.update(eps)
    sig2, D2 = other.update(eps)
    sig3, _ = third.update(eps)
    assert np.array_equal(sig, sig2) and np.array_equal(D, D2)
    assert np.array_equal(sig3[1], sig[1]) and not np.array_equal(sig3[2], sig[2])
    with pytest.raises(ValueError):
        paper.points(2).load_bytes(whole)
    with pytest.raises(mesorve.RveError) as info:
        paper.points(3).load_state(0, one[:-3])
    assert info.value.index == 0
    with pytest.raises(IndexError):
        points.state(3)


def test_threads_give_identical_results():
    model = mesorve.Model(IMPLEX)
    runs = []
    for threads in (1, 2, 0):
        points = model.points(6, threads=threads)
        out = []
        for step, dt in enumerate([1.0, 2.0, 0.5, 1.0, 3.0, 1.5]):
            sig, D = points.update(along(6, 6e-5 * (step + 1)), dtime=dt)
            points.commit()
            out.append((sig, D, points.report()["iterations"]))
        runs.append(out)
    for other in runs[1:]:
        for (s, d, i), (s2, d2, i2) in zip(runs[0], other):
            assert np.array_equal(s, s2) and np.array_equal(d, d2) and np.array_equal(i, i2)


def test_section_521_path_equals_rve_run(paper, tmp_path):
    subprocess.run([RVE, "run", "--quiet", "--out", str(tmp_path)], check=True)
    with open(tmp_path / "response.csv") as f:
        rows = list(csv.DictReader(f))
    path = paper.path()
    assert len(rows) == len(path) > 0
    points = paper.points(1)
    previous = np.zeros(3)
    for row, eps in zip(rows, path):
        assert np.array_equal(eps, [float(row[k]) for k in ("eps_xx", "eps_yy", "gamma_xy")])
        dt = np.linalg.norm(eps - previous)  # rve run's time increment
        previous = eps
        sig, D = points.update(eps[None, :], dtime=dt)
        points.commit()
        expected_sig = np.array([float(row[k]) for k in ("sig_xx", "sig_yy", "sig_xy")])
        expected_D = np.array([float(row[f"D{i}{j}"]) for i in (1, 2, 3) for j in (1, 2, 3)])
        scale = np.abs(expected_D).max()
        assert np.abs(sig[0] - expected_sig).max() <= 1e-12 * np.abs(expected_sig).max()
        assert np.abs(D[0].ravel() - expected_D).max() <= 1e-12 * scale
        assert points.report()["iterations"][0] == int(row["iterations"])


FRACTURE = str(ROOT / "scenes" / "concrete_fracture.toml")


def update_uniaxial(points, eps_xx, start, dtime, tol=1e-8, iterations=25):
    """The recipe of docs/python.md ("Uniaxial stress"): trial-updates `points` to the
    strains `eps_xx` (n,) with sigma_yy = sigma_xy = 0, by Newton's method on the free block
    of D from the strains `start` (n, 3). Returns (sig, D, eps)."""
    eps = np.array(start, dtype=float)
    eps[:, 0] = eps_xx
    for _ in range(iterations):
        sig, D = points.update(eps, dtime=dtime)
        free = sig[:, 1:]
        if np.abs(free).max() <= tol * max(np.abs(sig).max(), 1e-6):
            return sig, D, eps
        eps[:, 1:] -= np.linalg.solve(D[:, 1:, 1:], free[..., None])[..., 0]
    raise RuntimeError("the zero-stress components did not converge")


def test_uniaxial_stress_recipe_follows_rve_run_through_failure(tmp_path):
    subprocess.run([RVE, "run", FRACTURE, "--quiet", "--out", str(tmp_path),
                    "--set", "path.0.to=[2e-3, 0.0, 0.0]", "--set", "path.0.increments=200"],
                   check=True)
    with open(tmp_path / "response.csv") as f:
        rows = list(csv.DictReader(f))
    points = mesorve.Model(FRACTURE).points(1)
    eps = np.zeros((1, 3))
    got = []
    for row in rows:
        sig, _, eps = update_uniaxial(points, [float(row["eps_xx"])], eps, dtime=1e-5)
        points.commit()
        got.append(sig[0])
    expected = np.array([[float(r[k]) for k in ("sig_xx", "sig_yy", "sig_xy")] for r in rows])
    got = np.array(got)
    peak = expected[:, 0].max()
    assert 2.5 <= peak <= 4.5
    assert expected[-1, 0] < 0.5 * peak  # through the peak into the softening
    assert np.abs(got[:, 1:]).max() <= 1e-6 * peak
    assert np.abs(got[:, 0] - expected[:, 0]).max() <= 1e-4 * peak


def test_for_element_regularizes_the_failing_cell():
    """`Model.for_element(h)`: at the cell's own size (10 mm) the answers of the scene's
    model; an element half as large keeps more stress after the peak, a scene without
    `effects.regularization` refuses a length."""
    text = pathlib.Path(FRACTURE).read_text().replace(
        "paste_cracking = true", "paste_cracking = true\nregularization = true", 1)
    model = mesorve.Model(text=text)

    def tension(m):
        points = m.points(1)
        eps = np.zeros((1, 3))
        out = []
        for e in np.linspace(4e-5, 1.2e-3, 30):
            sig, _, eps = update_uniaxial(points, [e], eps, dtime=4e-5)
            points.commit()
            out.append(sig[0, 0])
        return np.array(out)

    own, half, scene = tension(model.for_element(10.0)), tension(model.for_element(5.0)), tension(model)
    assert np.array_equal(own, scene)
    peak = scene.max()
    top = int(np.argmax(scene))
    assert np.abs(half[:top + 1] - scene[:top + 1]).max() <= 1e-6 * peak
    assert half[-1] > scene[-1] + 0.01 * peak
    with pytest.raises(Exception, match="effects.regularization"):
        mesorve.Model(FRACTURE).for_element(5.0)
