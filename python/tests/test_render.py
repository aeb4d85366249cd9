"""The module's images are the command's: the same seed and settings give the same bits
as `trac0r render` (its PFM files, read without the module)."""
import os
import subprocess

import numpy as np
import pytest

import trac0r
from conftest import read_pfm


def cli_render(trac0r_bin, out, *args):
    subprocess.run([trac0r_bin, "render", *args, "--out", str(out)], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    return read_pfm(out)


def test_builtin_with_passes(tmp_path, trac0r_bin):
    out = tmp_path / "a.pfm"
    ref = cli_render(trac0r_bin, out, "--scene", "builtin:cornell", "--width", "64", "--height",
                     "48", "--spp", "4", "--seed", "7", "--passes", "albedo,normal,depth,id,variance")
    scene = trac0r.load("builtin:cornell", width=64, height=48)
    r = trac0r.render(scene, spp=4, seed=7, passes=["albedo", "normal", "depth", "id", "variance"])
    assert np.array_equal(r.image, ref)
    for name in ("albedo", "normal", "depth", "id", "variance"):
        pass_ref = read_pfm(tmp_path / f"a.{name}.pfm")
        mine = np.broadcast_to(r.passes[name].astype(np.float32), pass_ref.shape)
        assert np.array_equal(mine, pass_ref), name


@pytest.mark.parametrize("integrator", ["pt", "bdpt"])
def test_scene_file(tmp_path, trac0r_bin, source_dir, integrator):
    path = os.path.join(source_dir, "scenes", "cornell-classic.json")
    ref = cli_render(trac0r_bin, tmp_path / "f.pfm", path, "--width", "40", "--height", "30",
                     "--spp", "3", "--seed", "11", "--integrator", integrator)
    scene = trac0r.load(path, width=40, height=30)
    r = trac0r.render(scene, spp=3, seed=11, integrator=integrator)
    assert np.array_equal(r.image, ref)


def test_scene_file_defaults(tmp_path, trac0r_bin, source_dir):
    """The file's render block (size, spp, ...) applies to both alike."""
    path = os.path.join(source_dir, "scenes", "cornell-glass.json")
    scene = trac0r.load(path, width=32, height=24)
    ref = cli_render(trac0r_bin, tmp_path / "g.pfm", path, "--width", "32", "--height", "24",
                     "--spp", "2", "--seed", "1", "--max-depth", "6", "--sampler", "zsobol")
    r = trac0r.render(scene, spp=2, seed=1, max_depth=6, sampler="zsobol")
    assert np.array_equal(r.image, ref)


def test_denoise_and_time_limit_free(tmp_path, trac0r_bin):
    ref = cli_render(trac0r_bin, tmp_path / "d.pfm", "--scene", "builtin:cornell", "--width", "48",
                     "--height", "32", "--spp", "4", "--seed", "2", "--denoise")
    scene = trac0r.load("builtin:cornell", width=48, height=32)
    assert np.array_equal(trac0r.render(scene, spp=4, seed=2, denoise=True).image, ref)


def test_adaptive(tmp_path, trac0r_bin):
    ref = cli_render(trac0r_bin, tmp_path / "n.pfm", "--scene", "builtin:cornell", "--width", "32",
                     "--height", "32", "--spp", "64", "--seed", "4", "--noise-threshold", "0.2")
    scene = trac0r.load("builtin:cornell", width=32, height=32)
    r = trac0r.render(scene, spp=64, seed=4, noise_threshold=0.2)
    assert np.array_equal(r.image, ref)
    assert r.end in ("converged", "done")


def test_png_matches(tmp_path, trac0r_bin):
    subprocess.run([trac0r_bin, "render", "--scene", "builtin:cornell", "--width", "32", "--height",
                    "24", "--spp", "2", "--tonemap", "filmic", "--exposure", "0.5", "--out",
                    str(tmp_path / "c.png")], check=True, stderr=subprocess.DEVNULL)
    scene = trac0r.load("builtin:cornell", width=32, height=24)
    img = trac0r.render(scene, spp=2).image
    trac0r.write(tmp_path / "m.png", img, exposure=0.5, tonemap="filmic")
    assert np.array_equal(trac0r.read(tmp_path / "m.png"), trac0r.read(tmp_path / "c.png"))


def test_model_file(tmp_path, trac0r_bin):
    """A model file with the command's model options: up axis, scale, framing camera."""
    model = "/usr/share/assimp/models/Collada/duck.dae"
    if not os.path.exists(model):
        pytest.skip("assimp-testmodels is not installed")
    ref = cli_render(trac0r_bin, tmp_path / "m.pfm", model, "--up", "z", "--scale", "2",
                     "--camera", "frame", "--width", "40", "--height", "30", "--spp", "2")
    scene = trac0r.load(model, up="z", scale=2, camera="frame", width=40, height=30)
    assert np.array_equal(trac0r.render(scene, spp=2).image, ref)
    with pytest.raises(trac0r.Error):
        trac0r.load(model, camera="no-such-camera")


def test_stride(tmp_path, trac0r_bin):
    ref = cli_render(trac0r_bin, tmp_path / "s.pfm", "--scene", "builtin:cornell", "--width", "48",
                     "--height", "32", "--spp", "2", "--stride", "3")
    scene = trac0r.load("builtin:cornell", width=48, height=32)
    assert np.array_equal(trac0r.render(scene, spp=2, stride=3).image, ref)
    with pytest.raises(ValueError, match="stride"):
        trac0r.render(scene, stride=65)


def test_integrator_over_the_files_depth(tmp_path, trac0r_bin, source_dir):
    """Another integrator than the file's takes the file's max depth as the command does
    (cut to bdpt's limit), whether given to render() or assigned to the scene."""
    with open(os.path.join(source_dir, "scenes", "cornell-classic.json")) as f:
        text = f.read().replace('"max_depth": 64', '"max_depth": 3')
    path = tmp_path / "shallow.json"
    path.write_text(text)
    args = ["--width", "32", "--height", "24", "--spp", "2", "--integrator", "bdpt"]
    ref = cli_render(trac0r_bin, tmp_path / "b.pfm", str(path), *args)
    scene = trac0r.load(path, width=32, height=24)
    assert np.array_equal(trac0r.render(scene, spp=2, integrator="bdpt").image, ref)
    deep = os.path.join(source_dir, "scenes", "cornell-classic.json")
    ref = cli_render(trac0r_bin, tmp_path / "d.pfm", deep, *args)
    scene = trac0r.load(deep, width=32, height=24)
    scene.integrator = "bdpt"
    assert scene.max_depth == 15
    assert np.array_equal(trac0r.render(scene, spp=2).image, ref)
