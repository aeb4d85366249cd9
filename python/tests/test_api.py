"""Every function of the module with good and bad arguments: values, exception types and
the library's status codes they carry."""
import gc
import json
import os
import sys

import numpy as np
import pytest

import trac0r


def test_module_constants():
    assert trac0r.__version__.count(".") == 2
    assert "pt" in trac0r.INTEGRATORS and "bdpt" in trac0r.INTEGRATORS
    assert trac0r.RECON == ("off", "accumulate", "bilateral", "atrous", "svgf")
    assert "albedo" in trac0r.PASSES and "id" in trac0r.PASSES


def test_load_builtin_defaults(cornell):
    assert (cornell.width, cornell.height) == (64, 48)
    assert cornell.spp == 16 and cornell.integrator == "pt" and cornell.max_depth == 64
    assert cornell.triangles > 0 and cornell.accel == "bvh"
    cam = cornell.camera
    assert set(cam) == {"position", "direction", "up", "fov", "near", "far", "width", "height",
                        "aperture_radius", "focus_distance"}
    assert (cam["width"], cam["height"]) == (64, 48)


def test_scene_defaults_settable(cornell):
    cornell.spp = 3
    cornell.integrator = "naive"
    cornell.max_depth = 5
    assert (cornell.spp, cornell.integrator, cornell.max_depth) == (3, "naive", 5)
    r = trac0r.render(cornell)
    assert r.spp == 3
    with pytest.raises(ValueError, match="spp"):
        cornell.spp = 0
    with pytest.raises(ValueError, match="integrator"):
        cornell.integrator = "nope"
    with pytest.raises(TypeError, match="max_depth"):
        cornell.max_depth = "deep"


def test_camera_settable(cornell):
    before = trac0r.render(cornell, spp=1).image.copy()
    cam = cornell.camera
    cornell.camera = {"position": (0.0, 0.3, -1.0), "look_at": (0.0, 0.3, 0.0), "fov": 60}
    after = cornell.camera
    assert after["fov"] == pytest.approx(60.0)
    assert after["direction"] == pytest.approx((0.0, 0.0, 1.0))
    assert not np.array_equal(before, trac0r.render(cornell, spp=1).image)
    cornell.camera = cam
    assert np.array_equal(before, trac0r.render(cornell, spp=1).image)
    with pytest.raises(ValueError, match="unknown key"):
        cornell.camera = {"positon": (0, 0, 0)}
    with pytest.raises(ValueError, match=r"camera\['fov'\]"):
        cornell.camera = {"fov": 200}
    with pytest.raises(TypeError, match="camera"):
        cornell.camera = [1, 2, 3]
    with pytest.raises(trac0r.InvalidArgumentError):
        cornell.camera = {"direction": (0, 0, 0)}  # the library refuses a zero direction


def test_camera_lens(cornell):
    # A thin lens: set through the camera dict, kept when other keys change, and 0 renders
    # as the pinhole did.
    before = trac0r.render(cornell, spp=1).image.copy()
    cam = cornell.camera
    assert cam["aperture_radius"] == 0.0
    cornell.camera = {"aperture_radius": 0.05, "focus_distance": 2.0}
    cornell.camera = {"fov": cam["fov"]}
    after = cornell.camera
    assert after["aperture_radius"] == pytest.approx(0.05)
    assert after["focus_distance"] == pytest.approx(2.0)
    assert not np.array_equal(before, trac0r.render(cornell, spp=1).image)
    cornell.camera = {"aperture_radius": 0.0}
    assert np.array_equal(before, trac0r.render(cornell, spp=1).image)
    with pytest.raises(ValueError, match=r"camera\['aperture_radius'\]"):
        cornell.camera = {"aperture_radius": -1.0}
    with pytest.raises(ValueError, match=r"camera\['focus_distance'\]"):
        cornell.camera = {"focus_distance": 0.0}
    cornell.camera = cam


def test_resize(cornell):
    cornell.resize(32, 16)
    assert (cornell.width, cornell.height) == (32, 16)
    assert trac0r.render(cornell, spp=1).image.shape == (16, 32, 3)
    with pytest.raises(ValueError, match="width"):
        cornell.resize(0, 16)


def test_load_bad_arguments():
    with pytest.raises(ValueError, match="width"):
        trac0r.load("builtin:cornell", width=0)
    with pytest.raises(TypeError, match="height"):
        trac0r.load("builtin:cornell", height="tall")
    with pytest.raises(ValueError, match="up"):
        trac0r.load("builtin:cornell", up="x")
    with pytest.raises(ValueError, match="integrator"):
        trac0r.load("builtin:cornell", integrator="nope")
    with pytest.raises(ValueError, match="accel"):
        trac0r.load("builtin:cornell", accel="octree")
    with pytest.raises(TypeError, match="path"):
        trac0r.load(42)
    with pytest.raises(TypeError):
        trac0r.load("builtin:cornell", 64)  # options are keyword-only


def test_load_errors_carry_status(tmp_path):
    with pytest.raises(trac0r.NotFoundError) as e:
        trac0r.load(str(tmp_path / "missing.json"))
    assert e.value.status == 5 and e.value.status_name == "TR_STATUS_NOT_FOUND"
    assert isinstance(e.value, trac0r.Error) and isinstance(e.value, LookupError)
    bad = tmp_path / "bad.json"
    bad.write_text("{ not json")
    with pytest.raises(trac0r.ParseError) as e:
        trac0r.load(bad)  # os.PathLike
    assert e.value.status_name == "TR_STATUS_PARSE" and "bad.json" in str(e.value)
    with pytest.raises(trac0r.Error) as e:
        trac0r.load("builtin:no-such-scene")
    assert e.value.status != 0


def test_load_file_and_dict_agree(source_dir):
    path = os.path.join(source_dir, "scenes", "cornell-classic.json")
    with open(path) as f:
        d = json.load(f)
    a = trac0r.load(path, width=40, height=30)
    b = trac0r.load_dict(d, base_dir=os.path.dirname(path), width=40, height=30)
    assert (b.width, b.height) == (40, 30) and b.path == "<dict>"
    ra = trac0r.render(a, spp=2, seed=5)
    rb = trac0r.render(b, spp=2, seed=5)
    assert np.array_equal(ra.image, rb.image)


def test_load_dict_bad():
    with pytest.raises(TypeError, match="scene"):
        trac0r.load_dict([1, 2])
    with pytest.raises(TypeError, match="JSON"):
        trac0r.load_dict({"camera": object()})
    with pytest.raises(trac0r.ParseError) as e:
        trac0r.load_dict({"camera": 3})
    assert "<dict>" in str(e.value)


def test_render_result(cornell):
    r = trac0r.render(cornell, spp=2, passes=["albedo", "normal", "depth", "id", "variance"])
    assert isinstance(r, trac0r.Result)
    assert r.image.shape == (48, 64, 3) and r.image.dtype == np.float32
    assert r.spp == 2 and r.end == "done" and r.rays > 0 and r.seconds >= 0
    assert set(r.passes) == {"albedo", "normal", "depth", "id", "variance"}
    assert r.passes["depth"].shape == (48, 64, 1)
    assert r.passes["id"].dtype == np.uint32
    assert np.all(np.isfinite(r.image)) and r.image.max() > 0
    image, passes, spp, seconds, rays, end = r  # a named tuple
    assert spp == 2 and image is r.image


def test_render_bad_arguments(cornell):
    for kw, exc, name in [({"spp": 0}, ValueError, "spp"), ({"spp": "many"}, TypeError, "spp"),
                          ({"spp": 1.5}, TypeError, "spp"), ({"seed": -1}, ValueError, "seed"),
                          ({"integrator": "x"}, ValueError, "integrator"),
                          ({"max_depth": 0}, ValueError, "max_depth"),
                          ({"device": "gpu"}, ValueError, "device"),
                          ({"threads": -1}, ValueError, "threads"),
                          ({"sampler": "halton"}, ValueError, "sampler"),
                          ({"passes": ["nope"]}, ValueError, "passes"),
                          ({"passes": 3}, TypeError, "passes"),
                          ({"noise_threshold": 2.0}, ValueError, "noise_threshold"),
                          ({"noise_threshold": float("nan")}, ValueError, "noise_threshold"),
                          ({"time_limit": -1}, ValueError, "time_limit"),
                          ({"progress": 3}, TypeError, "progress")]:
        with pytest.raises(exc, match=name):
            trac0r.render(cornell, **kw)
    with pytest.raises(TypeError, match="scene"):
        trac0r.render(None)
    with pytest.raises(TypeError):
        trac0r.render(cornell, 4)  # keyword-only


def test_render_device_errors(cornell):
    with pytest.raises(trac0r.Error) as e:
        trac0r.render(cornell, spp=1, device="opencl:1023")
    assert e.value.status in (5, 8, 11)  # not found, unsupported (no OpenCL), device


def test_closed_scene():
    scene = trac0r.load("builtin:cornell", width=16, height=16)
    r = trac0r.render(scene, spp=1)
    scene.close()
    with pytest.raises(trac0r.InvalidOperationError):
        trac0r.render(scene)
    with pytest.raises(trac0r.InvalidOperationError):
        scene.camera
    assert r.image.sum() > 0  # the result keeps what it needs
    assert "closed" in repr(scene)


def test_views_no_copy(cornell):
    r = trac0r.render(cornell, spp=1, passes="albedo")
    owner = r.image.base
    assert type(owner).__name__ == "_Owner"
    assert not r.image.flags.owndata
    assert r.passes["albedo"].base is owner
    # The arrays lie on the session's film: the radiance over its sums, turned into means.
    assert r.image.ctypes.data == owner.buffers["sum"]
    assert r.passes["albedo"].ctypes.data == owner.buffers["albedo"]


def test_view_outlives_everything():
    scene = trac0r.load("builtin:cornell", width=32, height=24)
    r = trac0r.render(scene, spp=2, passes=["depth"])
    image = r.image
    expected = image.copy()
    depth = r.passes["depth"]
    del r, scene
    gc.collect()
    # Only the two arrays hold the owner now (sys.getrefcount counts its argument too).
    assert sys.getrefcount(image.base) == 4
    del depth
    gc.collect()
    assert sys.getrefcount(image.base) == 3
    junk = [np.ones((32, 24, 3), np.float32) * k for k in range(50)]  # reuse freed memory
    assert np.array_equal(image, expected)
    del junk


def test_large_result_is_not_copied():
    with trac0r.load("builtin:cornell", width=1920, height=1080) as scene:
        r = trac0r.render(scene, spp=1, max_depth=1)
    image = r.image
    assert image.shape == (1080, 1920, 3)
    assert not image.flags.owndata and type(image.base).__name__ == "_Owner"
    assert image.ctypes.data == image.base.buffers["sum"]
    assert image.strides == (1920 * 12, 12, 4)


def test_session_steps_equal_one_render(cornell):
    ref = trac0r.render(cornell, spp=4, seed=3, passes=["albedo"])
    with trac0r.Session(cornell, spp=4, seed=3, passes=["albedo"]) as s:
        p = s.run(samples=1)
        assert (p.samples, p.end) == (1, "paused")
        assert s.result().spp == 1
        p = s.run(samples=2)
        assert (p.samples, p.end) == (3, "paused")
        p = s.run()
        assert (p.samples, p.end) == (4, "done")
        res = s.result()
        assert np.array_equal(res.image, ref.image)
        assert np.array_equal(res.passes["albedo"], ref.passes["albedo"])
        assert res.image.flags.owndata is False
        assert s.progress.samples == 4
    with pytest.raises(trac0r.InvalidOperationError):
        s.run()
    with pytest.raises(ValueError, match="samples"):
        trac0r.Session(cornell).run(samples=0)


def test_denoise(cornell):
    r = trac0r.render(cornell, spp=2, denoise=True)
    noisy = trac0r.render(cornell, spp=2)
    assert r.image.shape == noisy.image.shape
    assert not np.array_equal(r.image, noisy.image)
    assert r.image.ctypes.data == r.image.base.buffers["image"]


def test_write_read_roundtrip(tmp_path, cornell):
    img = trac0r.render(cornell, spp=1).image
    trac0r.write(tmp_path / "a.pfm", img)
    assert np.array_equal(trac0r.read(tmp_path / "a.pfm"), img)
    trac0r.write(str(tmp_path / "a.exr"), img)
    assert np.array_equal(trac0r.read(tmp_path / "a.exr"), img)
    trac0r.write(tmp_path / "h.exr", img, half=True)
    assert np.allclose(trac0r.read(tmp_path / "h.exr"), img, rtol=1e-3, atol=1e-4)
    trac0r.write(tmp_path / "a.png", img, exposure=1.0)
    png = trac0r.read(tmp_path / "a.png")
    assert np.array_equal(np.round(png * 255).astype(np.uint8), trac0r.tonemap(img, exposure=1.0))
    gray = np.linspace(0, 1, 12, dtype=np.float64).reshape(3, 4)
    trac0r.write(tmp_path / "g.pfm", gray)
    back = trac0r.read(tmp_path / "g.pfm")
    assert back.shape == (3, 4, 3) and np.array_equal(back[..., 1], gray.astype(np.float32))


def test_write_read_errors(tmp_path):
    img = np.zeros((4, 4, 3), np.float32)
    with pytest.raises(ValueError, match="extension"):
        trac0r.write(tmp_path / "a.jpg", img)
    with pytest.raises(ValueError, match="image"):
        trac0r.write(tmp_path / "a.pfm", np.zeros((4, 4, 2), np.float32))
    with pytest.raises(TypeError, match="image"):
        trac0r.write(tmp_path / "a.pfm", "pixels")
    with pytest.raises(ValueError, match="tonemap"):
        trac0r.write(tmp_path / "a.png", img, tonemap="reinhard")
    with pytest.raises(trac0r.Error) as e:
        trac0r.write(tmp_path / "no" / "dir" / "a.pfm", img)
    assert e.value.status in (5, 6)
    with pytest.raises(trac0r.NotFoundError):
        trac0r.read(tmp_path / "missing.pfm")
    (tmp_path / "junk.pfm").write_bytes(b"P6\n1 1\n255\n000")
    with pytest.raises(trac0r.ParseError):
        trac0r.read(tmp_path / "junk.pfm")


def test_compare():
    rng = np.random.default_rng(1)
    a = rng.random((16, 24, 3), dtype=np.float32)
    m = trac0r.compare(a, a)
    assert m.psnr == float("inf") and m.mse == 0 and m.ssim == pytest.approx(1.0)
    b = np.clip(a + 0.1, 0, 1)
    m = trac0r.compare(b, a)
    assert 0 < m.mse < 0.011 and 19 < m.psnr < 30 and m.ssim < 1 and m.relmse > 0
    assert m.rmse == pytest.approx(m.mse ** 0.5)
    with pytest.raises(ValueError, match="reference"):
        trac0r.compare(a, a[:8])
    with pytest.raises(TypeError, match="image"):
        trac0r.compare(None, a)


def test_tonemap():
    img = np.array([[[0.0, 0.5, 1.0], [2.0, -1.0, float("nan")]]], np.float32)
    out = trac0r.tonemap(img)
    assert out.dtype == np.uint8 and out.shape == (1, 2, 3)
    assert out[0, 0, 0] == 0 and out[0, 0, 2] == 255 and out[0, 1, 0] == 255
    assert out[0, 1, 1] == 0 and out[0, 1, 2] == 0
    assert not np.array_equal(trac0r.tonemap(img, tonemap="filmic"), out)
    with pytest.raises(ValueError, match="exposure"):
        trac0r.tonemap(img, exposure=100)


def test_realtime(cornell):
    with trac0r.Realtime(cornell, width=32, height=24, recon="svgf", seed=1) as rt:
        f = rt.frame()
        assert isinstance(f, trac0r.Frame)
        assert f.image.shape == (24, 32, 3) and f.image.dtype == np.float32
        assert f.method == "svgf" and f.frame_spp == 1 and f.scale == 1.0
        assert f.render_ms >= 0 and f.temporal_ms >= 0 and f.spatial_ms >= 0
        cam = rt.camera
        pos = cam["position"]
        g = rt.frame(camera={"position": (pos[0] + 0.01, pos[1], pos[2])})
        assert not np.array_equal(f.image, g.image)
        off = rt.frame(recon="off")
        assert off.method == "off"
        with pytest.raises(ValueError, match="recon"):
            rt.frame(recon="magic")
        with pytest.raises(ValueError, match="camera"):
            rt.frame(camera={"width": 10})
    with pytest.raises(trac0r.InvalidOperationError):
        rt.frame()
    with pytest.raises(ValueError, match="recon"):
        trac0r.Realtime(cornell, recon="nope")
    with pytest.raises(ValueError, match="width"):
        trac0r.Realtime(cornell, width=0)


def test_realtime_deterministic(cornell):
    def run():
        with trac0r.Realtime(cornell, width=32, height=24, recon="atrous", seed=2) as rt:
            return [rt.frame().image for _ in range(3)]
    for a, b in zip(run(), run()):
        assert np.array_equal(a, b)
