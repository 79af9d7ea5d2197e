"""The Python package against the behaviour weft's CLI and Rust tests establish.

Run with `pytest crates/weft-py/tests` in an environment where the package is
installed (`pip install ./crates/weft-py[test]`). Tests that train a model need the
`weft` binary: set WEFT_BIN (weft-cli's python_package test does).
"""
import os
import subprocess

import numpy as np
import pytest

import weft


@pytest.fixture(scope="module")
def body():
    return weft.Body()


@pytest.fixture(scope="module")
def walk():
    return weft.procedural_motion("walk", frames=6, fps=30.0, seed=1)


@pytest.fixture(scope="module")
def skirt():
    return weft.generate_garment("skirt", vertices=300, seed=1)


def test_body_rest_and_pose(body):
    faces = body.faces
    assert faces.dtype == np.uint32 and faces.shape[1] == 3
    rest = body.rest()
    assert rest.shape == (body.vertex_count, 3) and rest.dtype == np.float32
    # The zero pose with a root translation is the rest body moved by it.
    poses = np.zeros((2, 24, 3), np.float32)
    trans = np.array([[0, 0, 0], [0.5, 0, -1]], np.float32)
    posed = body.pose(poses, trans)
    assert posed.shape == (2, body.vertex_count, 3)
    np.testing.assert_allclose(posed[0], rest, atol=1e-5)
    np.testing.assert_allclose(posed[1], rest + trans[1], atol=1e-5)
    # (T, 72) poses as AMASS stores them, and lists, are accepted.
    np.testing.assert_allclose(body.pose(poses.reshape(2, 72), trans.tolist()), posed)
    # A different shape changes the body.
    assert not np.allclose(body.rest([2.0]), rest)
    assert body.joints().shape == (24, 3)


def test_bad_input_names_the_field(body, tmp_path):
    with pytest.raises(ValueError, match="1 poses but 2 root translations"):
        body.pose(np.zeros((1, 24, 3)), np.zeros((2, 3)))
    with pytest.raises(ValueError, match=r"trans: shape .*expected \(N, 3\)"):
        body.pose(np.zeros((1, 24, 3)), np.zeros((1, 2)))
    with pytest.raises(ValueError, match="expected one of walk"):
        weft.procedural_motion("moonwalk")
    with pytest.raises(ValueError, match="missing.npz"):
        weft.load_motion(tmp_path / "missing.npz")
    with pytest.raises(ValueError, match="tinfoil"):
        weft.simulate(weft.generate_garment("skirt", vertices=300), weft.procedural_motion("walk", frames=2), material="tinfoil")
    with pytest.raises(ValueError, match="faces\\[0\\] names vertex 9"):
        weft.render([(np.zeros((3, 3)), [[0, 1, 9]])], width=32, height=32)


def test_motions_round_trip_through_files(walk, tmp_path):
    assert walk.frame_count == len(walk) == 6 and walk.fps == 30.0
    assert walk.poses.shape == (6, 24, 3) and walk.trans.shape == (6, 3)
    for name, up in [("walk.npz", "z"), ("walk_y.npz", "y"), ("walk.bvh", "z")]:
        path = tmp_path / name
        walk.save(path, npz_up=up)
        back = weft.load_motion(path)
        assert back.frame_count == 6
        np.testing.assert_allclose(back.trans, walk.trans, atol=1e-5)
        np.testing.assert_allclose(back.poses, walk.poses, atol=1e-4)
    half = weft.load_motion(tmp_path / "walk.npz", fps=15.0)
    assert half.fps == 15.0 and half.frame_count == 3
    own = weft.Motion(walk.poses, walk.trans, 30.0)
    np.testing.assert_array_equal(own.poses, walk.poses)


def test_garments_keep_their_uvs(skirt, tmp_path):
    assert skirt.kind == "skirt" and 250 <= skirt.vertex_count <= 350
    uvs = skirt.corner_uvs
    assert uvs.shape == (skirt.faces.shape[0], 3, 2)
    skirt.save(tmp_path / "skirt.obj")
    back = weft.load_garment(tmp_path / "skirt.obj")
    np.testing.assert_array_equal(back.positions, skirt.positions)
    np.testing.assert_array_equal(back.faces, skirt.faces)
    np.testing.assert_array_equal(back.corner_uvs, uvs)


def test_simulate_then_import_and_load(skirt, walk, body, tmp_path):
    frames, stats = weft.simulate(skirt, walk, material="silk", substeps=2, warmup=2)
    assert frames.shape == (6, skirt.vertex_count, 3) and frames.dtype == np.float32
    assert [s["frame"] for s in stats] == list(range(6))
    # The binding's check (the simulator's quality is weft-sim's tests): every frame
    # solved, nothing more than a centimetre inside the body.
    assert all(s["max_penetration"] < 1e-2 and s["newton_iterations"] > 0 for s in stats)
    # The skirt walks forward with the body (+Z).
    assert frames[-1, :, 2].mean() > frames[0, :, 2].mean() + 0.02

    # Two hem vertices across the skirt buttoned together come close; unbuttoned from
    # frame 1 they part again. A pair out of range is a ValueError, not a crash.
    hem = np.flatnonzero(skirt.positions[:, 1] < skirt.positions[:, 1].min() + 1e-3)
    a = hem[0]
    b = hem[np.argmax(np.linalg.norm(skirt.positions[hem] - skirt.positions[a], axis=1))]
    held, _ = weft.simulate(skirt, walk, material="silk", substeps=2, warmup=6, buttons=[(a, b)])
    undone, _ = weft.simulate(
        skirt, walk, material="silk", substeps=2, warmup=6, buttons=[(a, b)], unbutton_at=1
    )
    gap = lambda f: np.linalg.norm(f[:, a] - f[:, b], axis=1)
    assert gap(held)[0] < 0.5 * np.linalg.norm(skirt.positions[a] - skirt.positions[b])
    assert gap(undone)[-1] > 1.5 * gap(held)[-1]
    with pytest.raises(ValueError, match="button"):
        weft.simulate(skirt, walk, buttons=[(0, 10**6)])

    # The simulation as a dataset, through the import every weft model trains on.
    skirt.save(tmp_path / "skirt.obj")
    walk.save(tmp_path / "walk.npz")
    np.save(tmp_path / "walk.npy", frames)
    (tmp_path / "import.toml").write_text(
        'fps = 30\n[[garments]]\nid = "skirt"\ntemplate = "skirt.obj"\n'
        '[[sequences]]\ngarment = "skirt"\ncache = "walk.npy"\nmotion = "walk.npz"\nsplit = "train"\n'
    )
    ds = weft.import_dataset(tmp_path / "import.toml", tmp_path / "data")
    (record,) = ds.records("train")
    assert ds.records("test") == [] and len(ds) == 1
    seq = ds.load(record["id"], verify=True)
    np.testing.assert_array_equal(seq["positions"], frames)
    np.testing.assert_array_equal(seq["corner_uvs"], skirt.corner_uvs)
    np.testing.assert_allclose(seq["trans"], walk.trans, atol=1e-6)
    assert ds.body().vertex_count == body.vertex_count


def test_render_draws_the_garment(skirt, tmp_path):
    png = tmp_path / "skirt.png"
    image = weft.render([(skirt.positions, skirt.faces)], width=96, height=64, path=png)
    assert image.shape == (64, 96, 3) and image.dtype == np.uint8
    background = image[0, 0]
    drawn = np.any(image != background, axis=2).mean()
    assert 0.05 < drawn < 0.9, drawn
    assert png.read_bytes()[:4] == b"\x89PNG"


@pytest.mark.skipif(not os.environ.get("WEFT_BIN"), reason="needs the weft binary (WEFT_BIN) to train")
def test_a_trained_run_animates_any_garment(skirt, walk, tmp_path):
    # A two-step Multilevel run on a dataset of weft.simulate's output.
    frames, _ = weft.simulate(skirt, walk, material="silk", substeps=2, warmup=2)
    skirt.save(tmp_path / "skirt.obj")
    walk.save(tmp_path / "walk.npz")
    np.save(tmp_path / "walk.npy", frames)
    (tmp_path / "import.toml").write_text(
        'fps = 30\n[[garments]]\nid = "a"\ntemplate = "skirt.obj"\n[[garments]]\nid = "b"\ntemplate = "skirt.obj"\n'
        '[[sequences]]\ngarment = "a"\ncache = "walk.npy"\nmotion = "walk.npz"\nsplit = "train"\n'
        '[[sequences]]\ngarment = "b"\ncache = "walk.npy"\nmotion = "walk.npz"\nsplit = "validation"\n'
    )
    weft.import_dataset(tmp_path / "import.toml", tmp_path / "data")
    run = tmp_path / "run"
    subprocess.run(
        [os.environ["WEFT_BIN"], "train", "--data", str(tmp_path / "data"), "--out", str(run), "--steps", "2", "--quiet"],
        check=True,
    )
    model = weft.Run(run)
    assert model.name.startswith("Multilevel")
    dress = weft.generate_garment("dress", vertices=400, seed=3)
    out = model.animate(dress, walk)
    assert out.shape == (6, dress.vertex_count, 3) and np.isfinite(out).all()
