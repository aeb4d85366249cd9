"""Render a trac0r scene file with Blender's Cycles, for the comparison in docs/cycles.md.

    blender -b --factory-startup -P tools/cycles/render_scene.py -- SCENE.json \
        [--width 256] [--height 256] [--spp N] [--seed S] [--threads T] \
        [--time-limit SECONDS] --out OUT.exr|OUT.pfm
    for diagnosis only: [--max-bounces 1024] [--light-threshold 0.01] [--pattern pmj|sobol]
                        [--spot-model trac0r|cycles]

--max-bounces 0 is direct light only (as trac0r's --max-depth 2); --light-threshold is
Cycles' light_sampling_threshold (its default 0.01); --pattern picks Cycles' sampler. The
comparison keeps the defaults: 1024 bounces, where Cycles' Russian roulette ends the paths.
--spot-model cycles gives spots Cycles' own profile (spot size and blend) instead of
trac0r's, to show the difference between the two.

Blender is a measuring instrument here, never a dependency of trac0r: nothing in the build,
the tests or CI runs this script (docs/cycles.md says how the comparison is made).

What it maps, so that both renderers solve the same light transport problem:
  * shapes `quad`, `plane`, `box` (with position / orientation(_rad) / scale), as the
    triangles trac0r makes of them (a quad is (v0 v1 v2) and (v0 v2 v3): the classic box's
    walls are not planar, so the diagonal matters), in the scene's own units;
  * shapes `icosphere` (trac0r's own triangles, subdivided the same way; `smooth` with
    trac0r's corner normals as custom normals);
  * materials `diffuse` (Diffuse BSDF, roughness 0: Lambert; not the Principled BSDF, whose
    diffuse lobe is Burley's, not Lambert's), `principled` (the Principled BSDF of Blender
    3.4, Disney's model: another material, compared in docs/cycles.md, "The principled
    material") and `emitter` (Emission, radiance
    color x emittance; one-sided unless `two_sided`: Cycles 3.4's mesh emission is
    two-sided, so the strength is multiplied by 1 - Backfacing);
  * the camera: position, look_at / direction, up, vertical fov, near / far, handedness,
    and the thin lens (aperture_radius or f_number with sensor_height, focus_distance) as
    Blender's depth of field: the f-stop that gives the same radius with the lens set here;
  * a constant `environment` (the world's Background, colour x strength), the `sun`
    (a Sun light: angle, strength = irradiance) and punctual `lights`: point and spot
    lights of radius 0 and power 4 pi I watts, spots with trac0r's profile (see
    spot_profile), directional lights as Suns of angle 0.
Anything else (other shapes or materials, material extras, meshes, an environment map) is
refused with a message naming the field, and exit status 2, rather than rendered wrongly.

trac0r's world is right-handed with y up; Blender's is right-handed with z up, so a point
(x, y, z) goes to (x, -z, y), a rotation. A left-handed trac0r camera (the thesis's: right =
up x direction) sees the mirror image of what Blender's camera (right = direction x up)
sees; that scene is mirrored in x first, and its triangles re-wound so that their fronts
stay on the same physical side.

Cycles settings: CPU, path tracing with light sampling and MIS (its defaults), progressive
multi-jitter sampling, 1024 bounces of every kind (paths end by Cycles' own Russian
roulette, not by depth), no clamping, no glossy filter, no denoising, no adaptive
sampling, a 1-pixel box pixel filter (trac0r jitters uniformly in the pixel), a black
world unless the scene has an environment, Standard view transform, and the image written
as linear 32-bit float.
"""

import json
import math
import os
import struct
import sys
import time

import bpy
from mathutils import Matrix, Vector


class SceneError(Exception):
    pass


def fail(msg, code=2):
    sys.stderr.write("render_scene.py: %s\n" % msg)
    sys.stderr.flush()
    # Blender's own exit would run the rest of its command line; leave at once.
    os._exit(code)


def parse_args(argv):
    if "--" in argv:
        argv = argv[argv.index("--") + 1:]
    else:
        argv = []
    opts = {"width": 256, "height": 256, "spp": 16, "seed": 0, "threads": 0,
            "time_limit": 0.0, "max_bounces": 1024, "light_threshold": 0.01, "pattern": "pmj", "spot_model": "trac0r",
            "out": None, "scene": None}
    numeric = {"--width": ("width", int), "--height": ("height", int), "--spp": ("spp", int),
               "--seed": ("seed", int), "--threads": ("threads", int),
               "--time-limit": ("time_limit", float), "--max-bounces": ("max_bounces", int),
               "--light-threshold": ("light_threshold", float), "--pattern": ("pattern", str),
               "--spot-model": ("spot_model", str)}
    i = 0
    while i < len(argv):
        a = argv[i]
        if a in numeric or a == "--out":
            if i + 1 >= len(argv):
                fail("%s needs a value" % a)
            v = argv[i + 1]
            if a == "--out":
                opts["out"] = v
            else:
                key, conv = numeric[a]
                try:
                    opts[key] = conv(v)
                except ValueError:
                    fail("%s: expected a number, got '%s'" % (a, v))
            i += 2
        elif a.startswith("--"):
            fail("unknown option '%s'" % a)
        elif opts["scene"] is None:
            opts["scene"] = a
            i += 1
        else:
            fail("more than one scene file ('%s')" % a)
    if opts["scene"] is None or opts["out"] is None:
        fail("usage: blender -b --factory-startup -P render_scene.py -- SCENE.json "
             "[--width W] [--height H] [--spp N] [--seed S] [--threads T] "
             "[--time-limit SECONDS] [--max-bounces B] [--light-threshold X] "
             "[--pattern pmj|sobol] --out OUT.exr|OUT.pfm")
    if not (1 <= opts["width"] <= 16384 and 1 <= opts["height"] <= 16384):
        fail("--width/--height: expected 1..16384, got %dx%d" % (opts["width"], opts["height"]))
    if not (1 <= opts["spp"] <= 1 << 24):
        fail("--spp: expected 1..16777216, got %d" % opts["spp"])
    if opts["seed"] < 0 or opts["seed"] > 2**31 - 1:
        fail("--seed: expected 0..2147483647, got %d" % opts["seed"])
    if opts["threads"] < 0 or opts["threads"] > 1024:
        fail("--threads: expected 0 (all) .. 1024, got %d" % opts["threads"])
    if opts["spot_model"] not in ("trac0r", "cycles"):
        fail("--spot-model: expected trac0r or cycles, got '%s'" % opts["spot_model"])
    if opts["pattern"] not in ("pmj", "sobol"):
        fail("--pattern: expected pmj or sobol, got '%s'" % opts["pattern"])
    if not (0.0 <= opts["light_threshold"] <= 1.0):
        fail("--light-threshold: expected 0..1, got %s" % opts["light_threshold"])
    if not (0 <= opts["max_bounces"] <= 1024):
        fail("--max-bounces: expected 0..1024, got %d" % opts["max_bounces"])
    if not (opts["time_limit"] >= 0.0 and math.isfinite(opts["time_limit"])):
        fail("--time-limit: expected seconds >= 0, got %s" % opts["time_limit"])
    ext = os.path.splitext(opts["out"])[1].lower()
    if ext not in (".exr", ".pfm"):
        fail("--out: expected a .exr or .pfm file, got '%s'" % opts["out"])
    return opts


# ---- reading the trac0r scene ---------------------------------------------------------


def vec3(v, where):
    if (not isinstance(v, list) or len(v) != 3
            or not all(isinstance(e, (int, float)) and not isinstance(e, bool) for e in v)):
        raise SceneError("%s: expected [x, y, z], got %s" % (where, json.dumps(v)))
    return [float(e) for e in v]


def check_keys(obj, allowed, where):
    for k in obj:
        if k not in allowed:
            raise SceneError("%s.%s: not mapped to Cycles by this script (it maps %s)"
                             % (where, k, ", ".join(sorted(allowed))))


def rotate_xyz(p, a):
    """trac0r's rotation: about x, then y, then z (src/scene/shape.c)."""
    x, y, z = p
    c, s = math.cos(a[0]), math.sin(a[0])
    y, z = c * y - s * z, s * y + c * z
    c, s = math.cos(a[1]), math.sin(a[1])
    x, z = c * x + s * z, -s * x + c * z
    c, s = math.cos(a[2]), math.sin(a[2])
    x, y = c * x - s * y, s * x + c * y
    return [x, y, z]


def shape_transform(sh, where):
    pos = vec3(sh.get("position", [0, 0, 0]), where + ".position")
    if "orientation" in sh and "orientation_rad" in sh:
        raise SceneError("%s: both orientation and orientation_rad" % where)
    if "orientation_rad" in sh:
        ang = vec3(sh["orientation_rad"], where + ".orientation_rad")
    else:
        ang = [math.radians(e) for e in vec3(sh.get("orientation", [0, 0, 0]),
                                             where + ".orientation")]
    sc = sh.get("scale", 1)
    if isinstance(sc, (int, float)) and not isinstance(sc, bool):
        sc = [float(sc)] * 3
    else:
        sc = vec3(sc, where + ".scale")
    if not all(e > 0 for e in sc):
        raise SceneError("%s.scale: expected positive numbers, got %s" % (where, json.dumps(sc)))

    def apply(p):
        q = rotate_xyz([p[0] * sc[0], p[1] * sc[1], p[2] * sc[2]], ang)
        return [q[0] + pos[0], q[1] + pos[1], q[2] + pos[2]]
    return apply


def shape_normal_transform(sh, where):
    """Normals under the shape's transform: rotate(n / scale), normalized (shape.c)."""
    if "orientation_rad" in sh:
        ang = vec3(sh["orientation_rad"], where + ".orientation_rad")
    else:
        ang = [math.radians(e) for e in vec3(sh.get("orientation", [0, 0, 0]),
                                             where + ".orientation")]
    sc = sh.get("scale", 1)
    sc = [float(sc)] * 3 if isinstance(sc, (int, float)) else vec3(sc, where + ".scale")

    def apply(n):
        m = rotate_xyz([n[0] / sc[0], n[1] / sc[1], n[2] / sc[2]], ang)
        k = math.sqrt(sum(e * e for e in m))
        return [e / k for e in m]
    return apply


def unit_box_triangles():
    """The unit cube [-0.5, 0.5]^3, two triangles a face, fronts outward."""
    tris = []
    for axis in range(3):
        for side in (-1.0, 1.0):
            n = [0.0, 0.0, 0.0]
            n[axis] = 0.5 * side
            u = [0.0, 0.0, 0.0]
            v = [0.0, 0.0, 0.0]
            u[(axis + 1) % 3] = 0.5
            v[(axis + 2) % 3] = 0.5
            if side < 0:
                u = [-e for e in u]
            c = [[n[k] + su * u[k] + sv * v[k] for k in range(3)]
                 for su, sv in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
            tris.append((c[0], c[1], c[2]))
            tris.append((c[0], c[2], c[3]))
    return tris


def icosphere_triangles(levels):
    """trac0r's icosphere (src/scene/shape.c, gen_icosphere): the unit icosahedron with
    the same vertices and faces, each triangle split in four `levels` times, the new
    vertices normalized onto the unit sphere, in the same order."""
    g = 1.6180339887498949
    v = [(-1, g, 0), (1, g, 0), (-1, -g, 0), (1, -g, 0), (0, -1, g), (0, 1, g), (0, -1, -g),
         (0, 1, -g), (g, 0, -1), (g, 0, 1), (-g, 0, -1), (-g, 0, 1)]

    def unit(p):
        n = math.sqrt(sum(e * e for e in p))
        return [e / n for e in p]
    v = [unit(p) for p in v]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
         (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    tris = [(v[a], v[b], v[c]) for a, b, c in f]
    for _ in range(levels):
        nxt = []
        for a, b, c in tris:
            ab = unit([a[k] + b[k] for k in range(3)])
            bc = unit([b[k] + c[k] for k in range(3)])
            ca = unit([c[k] + a[k] for k in range(3)])
            nxt += [(a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca)]
        tris = nxt
    return tris


def shape_triangles(sh, where):
    """The shape's triangles in world coordinates, and for a smooth icosphere the normal
    at each corner (trac0r's: the sphere's own, through the inverse transpose), else None."""
    t = sh.get("type")
    common = {"type", "name", "position", "orientation", "orientation_rad", "scale", "material"}
    normals = None
    if t == "quad":
        check_keys(sh, common | {"vertices"}, where)
        vs = sh.get("vertices")
        if not isinstance(vs, list) or len(vs) != 4:
            raise SceneError("%s.vertices: expected 4 corners" % where)
        c = [vec3(v, "%s.vertices[%d]" % (where, i)) for i, v in enumerate(vs)]
        local = [(c[0], c[1], c[2]), (c[0], c[2], c[3])]
    elif t == "plane":
        check_keys(sh, common, where)
        a, b = [-0.5, 0.0, -0.5], [0.5, 0.0, -0.5]
        c, d = [0.5, 0.0, 0.5], [-0.5, 0.0, 0.5]
        local = [(a, c, b), (a, d, c)]
    elif t == "box":
        check_keys(sh, common, where)
        local = unit_box_triangles()
    elif t == "icosphere":
        check_keys(sh, common | {"subdivisions", "smooth"}, where)
        sub = sh.get("subdivisions", 2)
        if not isinstance(sub, int) or isinstance(sub, bool) or not 0 <= sub <= 7:
            raise SceneError("%s.subdivisions: expected an integer in [0, 7]" % where)
        smooth = sh.get("smooth", False)
        if not isinstance(smooth, bool):
            raise SceneError("%s.smooth: expected true or false" % where)
        local = icosphere_triangles(sub)
        if smooth:
            normals = local
    else:
        raise SceneError("%s.type: '%s' is not mapped to Cycles by this script "
                         "(it maps quad, plane, box, icosphere)" % (where, t))
    f = shape_transform(sh, where)
    tris = [tuple(f(p) for p in tri) for tri in local]
    if normals is not None:
        g = shape_normal_transform(sh, where)
        normals = [tuple(g(n) for n in tri) for tri in normals]
    return tris, normals


def read_materials(mats):
    if not isinstance(mats, dict):
        raise SceneError("materials: expected an object")
    out = {}
    for name, m in mats.items():
        where = "materials.%s" % name
        if not isinstance(m, dict):
            raise SceneError("%s: expected an object" % where)
        t = m.get("type")
        if t == "diffuse":
            check_keys(m, {"type", "color"}, where)
            col = vec3(m.get("color"), where + ".color")
            out[name] = {"type": t, "color": col}
        elif t == "emitter":
            check_keys(m, {"type", "color", "emittance", "two_sided"}, where)
            col = vec3(m.get("color"), where + ".color")
            e = m.get("emittance")
            if not isinstance(e, (int, float)) or isinstance(e, bool) or not e > 0:
                raise SceneError("%s.emittance: expected a number > 0" % where)
            two = m.get("two_sided", False)
            if not isinstance(two, bool):
                raise SceneError("%s.two_sided: expected true or false" % where)
            out[name] = {"type": t, "color": col, "emittance": float(e), "two_sided": two}
        elif t == "principled":
            check_keys(m, {"type", "color", "roughness", "metallic", "multiscatter", "ior",
                           "clearcoat", "clearcoat_roughness", "sheen_color",
                           "sheen_roughness"}, where)
            pm = {"type": t, "color": vec3(m.get("color"), where + ".color"),
                  "roughness": number(m, "roughness", 0, 1, 1, where),
                  "metallic": number(m, "metallic", 0, 1, 0, where),
                  "ior": number(m, "ior", 1, 10, 1.5, where),
                  "clearcoat": number(m, "clearcoat", 0, 1, 0, where),
                  "clearcoat_roughness": number(m, "clearcoat_roughness", 0, 1, 0, where),
                  "sheen_roughness": number(m, "sheen_roughness", 0, 1, 0, where),
                  "multiscatter": m.get("multiscatter", True)}
            if not isinstance(pm["multiscatter"], bool):
                raise SceneError("%s.multiscatter: expected true or false" % where)
            sheen = vec3(m.get("sheen_color", [0, 0, 0]), where + ".sheen_color")
            if max(sheen) - min(sheen) > 0:
                raise SceneError("%s.sheen_color: the Principled BSDF's sheen is white or "
                                 "tinted towards the base colour; only a grey sheen is mapped"
                                 % where)
            pm["sheen"] = sheen[0]
            out[name] = pm
        else:
            raise SceneError("%s.type: '%s' is not mapped to Cycles by this script "
                             "(it maps diffuse, emitter, principled)" % (where, t))
    return out


def number(obj, key, lo, hi, default, where):
    v = obj.get(key, default)
    if (not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v)
            or not lo <= v <= hi):
        raise SceneError("%s.%s: expected a number in [%g, %g], got %s"
                         % (where, key, lo, hi, json.dumps(v)))
    return float(v)


def colour(obj, key, default, where):
    c = vec3(obj.get(key, default), "%s.%s" % (where, key))
    if not all(0.0 <= e <= 1e7 for e in c):
        raise SceneError("%s.%s: expected three numbers in [0, 1e7]" % (where, key))
    return c


def direction(obj, key, where):
    if key not in obj:
        raise SceneError("%s.%s: required" % (where, key))
    d = vec3(obj[key], "%s.%s" % (where, key))
    n = math.sqrt(sum(e * e for e in d))
    if not n > 0:
        raise SceneError("%s.%s: expected a non-zero vector" % (where, key))
    return [e / n for e in d]


def read_lens(cam, fov, look_dist):
    """trac0r's thin lens (docs/scene-format.md, Depth of field) as a radius in scene units
    and the focus plane's distance along the view direction; (0, 0) for a pinhole."""
    if "aperture_radius" in cam and "f_number" in cam:
        raise SceneError("camera: expected at most one of aperture_radius and f_number")
    if "sensor_height" in cam and "f_number" not in cam:
        raise SceneError("camera.sensor_height: only means something with camera.f_number")
    radius = number(cam, "aperture_radius", 0.0, 1e30, 0.0, "camera")
    if "f_number" in cam:
        n = number(cam, "f_number", 0.01, 1e30, 1.0, "camera")
        sensor = number(cam, "sensor_height", 1e-30, 1e30, 0.024, "camera")
        # The focal length of a lens whose image of height sensor_height spans the fov.
        radius = sensor / (2.0 * math.tan(math.radians(fov) / 2.0)) / (2.0 * n)
    if not radius > 0.0:
        return 0.0, 0.0
    if "focus_distance" in cam:
        focus = number(cam, "focus_distance", 1e-30, 1e30, 1.0, "camera")
    elif look_dist > 0.0:
        focus = look_dist
    else:
        raise SceneError("camera.focus_distance: required with an aperture and 'direction'")
    return radius, focus


def read_environment(env):
    """A constant environment: radiance color x strength. A map is refused."""
    where = "environment"
    if not isinstance(env, dict):
        raise SceneError("%s: expected an object" % where)
    check_keys(env, {"color", "strength", "rotation"}, where)
    if "color" not in env:
        raise SceneError("%s.color: required (maps are not mapped to Cycles)" % where)
    c = colour(env, "color", [1, 1, 1], where)
    k = number(env, "strength", 0.0, 1e7, 1.0, where)
    # A rotation turns a constant colour into itself.
    number(env, "rotation", -360.0, 360.0, 0.0, where)
    return [e * k for e in c]


def read_sun(sun):
    where = "sun"
    if not isinstance(sun, dict):
        raise SceneError("%s: expected an object" % where)
    check_keys(sun, {"direction", "angle", "irradiance"}, where)
    d = direction(sun, "direction", where)
    angle = number(sun, "angle", 0.001, 90.0, 0.526, where)
    e = sun.get("irradiance", 1.0)
    if isinstance(e, list):
        e = colour(sun, "irradiance", None, where)
    else:
        e = [number(sun, "irradiance", 0.0, 1e7, 1.0, where)] * 3
    return {"towards": d, "angle": angle, "irradiance": e}


def read_lights(lights):
    if not isinstance(lights, list):
        raise SceneError("lights: expected an array")
    out = []
    for i, l in enumerate(lights):
        where = "lights[%d]" % i
        if not isinstance(l, dict):
            raise SceneError("%s: expected an object" % where)
        t = l.get("type")
        if t == "point":
            check_keys(l, {"type", "name", "position", "color", "intensity"}, where)
        elif t == "spot":
            check_keys(l, {"type", "name", "position", "direction", "color", "intensity",
                           "cone_angle", "blend"}, where)
        elif t == "directional":
            check_keys(l, {"type", "name", "direction", "color", "irradiance"}, where)
        else:
            raise SceneError("%s.type: expected point, spot or directional, got %s"
                             % (where, json.dumps(t)))
        light = {"type": t, "color": colour(l, "color", [1, 1, 1], where)}
        if t in ("point", "spot"):
            if "position" not in l:
                raise SceneError("%s.position: required" % where)
            light["position"] = vec3(l["position"], where + ".position")
            light["intensity"] = number(l, "intensity", 0.0, 1e7, 1.0, where)
        if t in ("spot", "directional"):
            light["direction"] = direction(l, "direction", where)
        if t == "spot":
            light["cone_angle"] = number(l, "cone_angle", 0.001, 180.0, 45.0, where)
            if light["cone_angle"] < 1.0:
                raise SceneError("%s.cone_angle: Blender's spot size is at least 1 degree"
                                 % where)
            light["blend"] = number(l, "blend", 0.0, 1.0, 0.15, where)
        if t == "directional":
            light["irradiance"] = number(l, "irradiance", 0.0, 1e7, 1.0, where)
        out.append(light)
    return out


def read_scene(path):
    try:
        with open(path, "r", encoding="utf-8") as fh:
            doc = json.load(fh)
    except OSError as e:
        raise SceneError("%s: %s" % (path, e.strerror))
    except ValueError as e:
        raise SceneError("%s: not JSON: %s" % (path, e))
    if not isinstance(doc, dict):
        raise SceneError("%s: expected an object at the top" % path)
    check_keys(doc, {"version", "description", "render", "camera", "materials", "shapes",
                     "environment", "sun", "lights"}, "(top level)")
    mats = read_materials(doc.get("materials"))
    cam = doc.get("camera")
    if not isinstance(cam, dict):
        raise SceneError("camera: missing or not an object")
    check_keys(cam, {"position", "look_at", "direction", "up", "fov", "near", "far",
                     "handedness", "aperture_radius", "f_number", "sensor_height",
                     "focus_distance"}, "camera")
    pos = vec3(cam.get("position"), "camera.position")
    if ("look_at" in cam) == ("direction" in cam):
        raise SceneError("camera: expected exactly one of look_at and direction")
    if "look_at" in cam:
        la = vec3(cam["look_at"], "camera.look_at")
        d = [la[k] - pos[k] for k in range(3)]
    else:
        d = vec3(cam["direction"], "camera.direction")
    fov = cam.get("fov")
    if not isinstance(fov, (int, float)) or not 0 < fov < 180:
        raise SceneError("camera.fov: expected degrees in (0, 180), got %s" % json.dumps(fov))
    hand = cam.get("handedness", "left")
    if hand not in ("left", "right"):
        raise SceneError("camera.handedness: expected left or right, got %s" % json.dumps(hand))
    camera = {"pos": pos, "dir": d, "up": vec3(cam.get("up", [0, 1, 0]), "camera.up"),
              "fov": float(fov), "near": float(cam.get("near", 0.001)),
              "far": float(cam.get("far", 1e30)), "right_handed": hand == "right"}
    look_dist = math.sqrt(sum(e * e for e in d)) if "look_at" in cam else 0.0
    camera["lens_radius"], camera["focus"] = read_lens(cam, float(fov), look_dist)
    shapes = doc.get("shapes", [])
    if not isinstance(shapes, list) or not shapes:
        raise SceneError("shapes: expected a non-empty array")
    by_mat = {}
    for i, sh in enumerate(shapes):
        where = "shapes[%d]" % i
        if not isinstance(sh, dict):
            raise SceneError("%s: expected an object" % where)
        m = sh.get("material")
        if m not in mats:
            raise SceneError("%s.material: unknown material %s" % (where, json.dumps(m)))
        tris, normals = shape_triangles(sh, where)
        by_mat.setdefault(m, []).extend(
            zip(tris, normals if normals is not None else [None] * len(tris)))
    lights = {"environment": read_environment(doc["environment"]) if "environment" in doc
              else None,
              "sun": read_sun(doc["sun"]) if "sun" in doc else None,
              "punctual": read_lights(doc.get("lights", []))}
    return mats, camera, by_mat, lights


# ---- building it in Blender -----------------------------------------------------------


def to_blender(p, mirror):
    """trac0r (x, y up, z) to Blender (x, y, z up); mirrored in x for a left-handed camera."""
    x = -p[0] if mirror else p[0]
    return (x, -p[2], p[1])


def make_material(name, m):
    mat = bpy.data.materials.new("tr_" + name)
    mat.use_nodes = True
    nt = mat.node_tree
    for n in list(nt.nodes):
        nt.nodes.remove(n)
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    out.target = "CYCLES"
    if m["type"] == "diffuse":
        bsdf = nt.nodes.new("ShaderNodeBsdfDiffuse")
        bsdf.inputs["Color"].default_value = (*m["color"], 1.0)
        bsdf.inputs["Roughness"].default_value = 0.0
        nt.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    elif m["type"] == "principled":
        # Blender 3.4's Principled BSDF (v1, Disney's model); docs/cycles.md lists where it
        # and trac0r's glTF material differ.
        bsdf = nt.nodes.new("ShaderNodeBsdfPrincipled")
        bsdf.distribution = "MULTI_GGX" if m["multiscatter"] else "GGX"
        i = bsdf.inputs
        i["Base Color"].default_value = (*m["color"], 1.0)
        i["Metallic"].default_value = m["metallic"]
        i["Roughness"].default_value = m["roughness"]
        # Specular s gives the dielectric F0 = 0.08 s: glTF's ((ior - 1) / (ior + 1))^2.
        f0 = ((m["ior"] - 1.0) / (m["ior"] + 1.0)) ** 2
        i["Specular"].default_value = f0 / 0.08
        i["Specular Tint"].default_value = 0.0
        i["IOR"].default_value = m["ior"]
        i["Clearcoat"].default_value = m["clearcoat"]
        i["Clearcoat Roughness"].default_value = m["clearcoat_roughness"]
        i["Sheen"].default_value = m["sheen"]
        i["Sheen Tint"].default_value = 0.0
        for k in ("Subsurface", "Transmission", "Anisotropic"):
            i[k].default_value = 0.0
        nt.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
        return mat
    else:
        em = nt.nodes.new("ShaderNodeEmission")
        em.inputs["Color"].default_value = (*m["color"], 1.0)
        if m["two_sided"]:
            em.inputs["Strength"].default_value = m["emittance"]
        else:
            # Strength = emittance * (1 - backfacing): only the front face emits.
            geo = nt.nodes.new("ShaderNodeNewGeometry")
            front = nt.nodes.new("ShaderNodeMath")
            front.operation = "SUBTRACT"
            front.inputs[0].default_value = 1.0
            nt.links.new(geo.outputs["Backfacing"], front.inputs[1])
            strength = nt.nodes.new("ShaderNodeMath")
            strength.operation = "MULTIPLY"
            strength.inputs[1].default_value = m["emittance"]
            nt.links.new(front.outputs["Value"], strength.inputs[0])
            nt.links.new(strength.outputs["Value"], em.inputs["Strength"])
        nt.links.new(em.outputs["Emission"], out.inputs["Surface"])
    # Multiple importance sampling of the mesh light (Cycles' default, said explicitly).
    mat.cycles.sample_as_light = True
    return mat


def aim(z):
    """A rotation whose local +z is the unit vector z (Blender's lights shine down -z)."""
    z = Vector(z).normalized()
    helper = Vector((0.0, 0.0, 1.0)) if abs(z.z) < 0.9 else Vector((1.0, 0.0, 0.0))
    x = helper.cross(z).normalized()
    y = z.cross(x)
    m = Matrix.Identity(4)
    for r in range(3):
        m[r][0], m[r][1], m[r][2] = x[r], y[r], z[r]
    return m


def add_light(scene, name, kind, rgb, at=None, shine=None):
    """A Blender light of colour x energy = rgb (the colour normalised to its largest
    channel, the rest in the energy), at a point, shining along `shine` (Blender coords)."""
    top = max(rgb)
    ld = bpy.data.lights.new("tr_" + name, kind)
    ld.color = tuple(e / top for e in rgb) if top > 0 else (1.0, 1.0, 1.0)
    ld.energy = top
    ld.use_shadow = True
    ld.cycles.cast_shadow = True
    ld.cycles.use_multiple_importance_sampling = True
    ob = bpy.data.objects.new("tr_" + name, ld)
    m = aim([-e for e in shine]) if shine is not None else Matrix.Identity(4)
    if at is not None:
        for r in range(3):
            m[r][3] = at[r]
    ob.matrix_world = m
    scene.collection.objects.link(ob)
    return ld


def build_lights(scene, lights, mirror, spot_model):
    """The environment, the sun and the punctual lights (the mapping in docs/cycles.md)."""
    world = bpy.data.worlds.new("tr_world")
    env = lights["environment"]
    if env is None or max(env) <= 0:
        world.use_nodes = False
        world.color = (0.0, 0.0, 0.0)
        world.cycles.sampling_method = "NONE"
    else:
        # Background colour x strength is the radiance of every direction, as trac0r's
        # constant environment; sampled as a light with MIS (Cycles' automatic map).
        world.use_nodes = True
        nt = world.node_tree
        for n in list(nt.nodes):
            nt.nodes.remove(n)
        bg = nt.nodes.new("ShaderNodeBackground")
        top = max(env)
        bg.inputs["Color"].default_value = (*[e / top for e in env], 1.0)
        bg.inputs["Strength"].default_value = top
        out = nt.nodes.new("ShaderNodeOutputWorld")
        out.target = "CYCLES"
        nt.links.new(bg.outputs["Background"], out.inputs["Surface"])
        world.cycles.sampling_method = "AUTOMATIC"
    scene.world = world

    sun = lights["sun"]
    if sun is not None and max(sun["irradiance"]) > 0:
        # Cycles' sun: strength is the irradiance on a surface facing it (W/m^2), angle
        # the disc's angular diameter; it shines along its local -z, away from the sun.
        ld = add_light(scene, "sun", "SUN", sun["irradiance"],
                       shine=[-e for e in to_blender(sun["towards"], mirror)])
        ld.angle = math.radians(sun["angle"])
    for i, l in enumerate(lights["punctual"]):
        name = "light%d" % i
        if l["type"] == "directional":
            ld = add_light(scene, name, "SUN", [c * l["irradiance"] for c in l["color"]],
                           shine=to_blender(l["direction"], mirror))
            ld.angle = 0.0
            continue
        # Cycles' point and spot lights have an intensity of power / (4 pi) W/sr: their
        # kernels' eval_fac is 1 / (4 pi) per unit of strength (radius 0: a point).
        power = [4.0 * math.pi * l["intensity"] * c for c in l["color"]]
        at = to_blender(l["position"], mirror)
        if max(power) <= 0:
            continue
        if l["type"] == "point":
            ld = add_light(scene, name, "POINT", power, at=at)
        else:
            ld = add_light(scene, name, "SPOT", power, at=at,
                           shine=to_blender(l["direction"], mirror))
            ld.spot_size = math.radians(l["cone_angle"])
            if spot_model == "cycles":
                ld.spot_blend = l["blend"]
            else:
                spot_profile(ld, l["cone_angle"], l["blend"])
        ld.shadow_soft_size = 0.0


def spot_profile(ld, cone_angle, blend):
    """trac0r's spot profile on a Cycles spot. Cycles 3.4's spot (kernel/light/spot.h)
    multiplies its strength by cos(a) (a the angle from the axis) inside the cone, and
    fades in by smoothstep((cos a - cos h) / ((1 - cos h) blend)); trac0r's has no cos(a)
    and fades in by smoothstep((cos a - cos h) / (cos(h (1 - blend)) - cos h)) (h the
    half-angle). So Cycles' blend is set to 0 (a hard edge at h) and the light's emission
    strength is trac0r's profile / cos(a), cos(a) read from the light's Normal texture
    coordinate: the direction from the light to the point lit, in the light's own axes,
    where the spot shines down -z."""
    h = math.radians(cone_angle) / 2.0
    cos_h = math.cos(h)
    width = math.cos(h * (1.0 - blend)) - cos_h
    ld.spot_blend = 0.0
    ld.use_nodes = True
    nt = ld.node_tree
    for n in list(nt.nodes):
        nt.nodes.remove(n)

    def math_node(op, a, b=None, clamp=False):
        m = nt.nodes.new("ShaderNodeMath")
        m.operation = op
        m.use_clamp = clamp
        for k, v in ((0, a), (1, b)):
            if v is None:
                continue
            if isinstance(v, float):
                m.inputs[k].default_value = v
            else:
                nt.links.new(v, m.inputs[k])
        return m.outputs["Value"]

    tc = nt.nodes.new("ShaderNodeTexCoord")
    sep = nt.nodes.new("ShaderNodeSeparateXYZ")
    nt.links.new(tc.outputs["Normal"], sep.inputs["Vector"])
    cos_a = math_node("MULTIPLY", sep.outputs["Z"], -1.0)
    if width > 0.0:
        t = math_node("DIVIDE", math_node("SUBTRACT", cos_a, cos_h), width, clamp=True)
        # smoothstep: t^2 (3 - 2 t)
        s = math_node("MULTIPLY", math_node("MULTIPLY", t, t),
                      math_node("SUBTRACT", 3.0, math_node("MULTIPLY", t, 2.0)))
    else:
        s = math_node("GREATER_THAN", cos_a, cos_h)
    strength = math_node("DIVIDE", s, math_node("MAXIMUM", cos_a, 1e-6))
    em = nt.nodes.new("ShaderNodeEmission")
    em.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    nt.links.new(strength, em.inputs["Strength"])
    out = nt.nodes.new("ShaderNodeOutputLight")
    out.target = "CYCLES"
    nt.links.new(em.outputs["Emission"], out.inputs["Surface"])


def build(scene, mats, camera, by_mat, lights, spot_model):
    mirror = not camera["right_handed"]
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj, do_unlink=True)
    for name, tris in by_mat.items():
        verts, faces, vnormals = [], [], []
        smooth = any(n is not None for _, n in tris)
        for tri, nrm in tris:
            base = len(verts)
            verts.extend(to_blender(p, mirror) for p in tri)
            # A mirror turns the winding round; re-wind to keep the front where it was.
            faces.append((base, base + 2, base + 1) if mirror else (base, base + 1, base + 2))
            if smooth:
                if nrm is None:
                    a, b, c = (Vector(to_blender(p, mirror)) for p in tri)
                    fn = (b - a).cross(c - a) * (-1.0 if mirror else 1.0)
                    nrm = [None] * 3
                    vnormals.extend([tuple(fn.normalized())] * 3)
                else:
                    vnormals.extend(to_blender(n, mirror) for n in nrm)
        me = bpy.data.meshes.new("tr_" + name)
        me.from_pydata(verts, [], faces)
        me.validate()
        if smooth:
            # A smooth icosphere's corner normals, trac0r's own (no vertex is shared, so
            # they are set per vertex as custom normals).
            me.use_auto_smooth = True
            for poly in me.polygons:
                poly.use_smooth = True
            me.normals_split_custom_set_from_vertices(vnormals)
        me.materials.append(make_material(name, mats[name]))
        ob = bpy.data.objects.new("tr_" + name, me)
        scene.collection.objects.link(ob)

    build_lights(scene, lights, mirror, spot_model)

    pos = Vector(to_blender(camera["pos"], mirror))
    d = Vector(to_blender(camera["dir"], mirror))
    up = Vector(to_blender(camera["up"], mirror))
    if d.length == 0:
        raise SceneError("camera: zero view direction")
    d.normalize()
    right = d.cross(up)
    if right.length < 1e-6:
        raise SceneError("camera.up: parallel to the view direction")
    right.normalize()
    cup = right.cross(d)
    # Blender's camera looks down its local -z with local +y up, so its right is
    # direction x up: a right-handed trac0r camera.
    m = Matrix.Identity(4)
    for r in range(3):
        m[r][0], m[r][1], m[r][2], m[r][3] = right[r], cup[r], -d[r], pos[r]
    cd = bpy.data.cameras.new("tr_camera")
    cd.type = "PERSP"
    cd.sensor_fit = "VERTICAL"
    cd.sensor_height = 24.0
    cd.lens = cd.sensor_height / (2.0 * math.tan(math.radians(camera["fov"]) / 2.0))
    cd.shift_x = cd.shift_y = 0.0
    # Cycles clips at z depths, trac0r at ray distances: the same wherever nothing lies
    # nearer than `near` to the camera (true of every scene it is meant for).
    cd.clip_start = max(camera["near"], 1e-6)
    cd.clip_end = min(camera["far"], 1e30)
    if camera["lens_radius"] > 0:
        # Cycles' thin lens: radius = lens (mm) * 1e-3 / (2 f-stop) in scene units, a disc
        # (no blades), focused on the plane focus_distance along the view direction.
        cd.dof.use_dof = True
        cd.dof.focus_object = None
        cd.dof.focus_distance = camera["focus"]
        cd.dof.aperture_fstop = cd.lens * 1e-3 / (2.0 * camera["lens_radius"])
        cd.dof.aperture_blades = 0
        cd.dof.aperture_ratio = 1.0
        cd.dof.aperture_rotation = 0.0
    else:
        cd.dof.use_dof = False
    cam = bpy.data.objects.new("tr_camera", cd)
    cam.matrix_world = m
    scene.collection.objects.link(cam)
    scene.camera = cam


def configure(scene, opts):
    r = scene.render
    r.engine = "CYCLES"
    r.resolution_x = opts["width"]
    r.resolution_y = opts["height"]
    r.resolution_percentage = 100
    r.pixel_aspect_x = r.pixel_aspect_y = 1.0
    r.use_border = False
    r.use_compositing = False
    r.use_sequencer = False
    r.use_persistent_data = False
    r.film_transparent = False
    if opts["threads"] > 0:
        r.threads_mode = "FIXED"
        r.threads = opts["threads"]
    else:
        r.threads_mode = "AUTO"
    c = scene.cycles
    c.device = "CPU"
    c.feature_set = "SUPPORTED"
    c.progressive = "PATH"
    c.samples = opts["spp"]
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.sampling_pattern = {"pmj": "PROGRESSIVE_MULTI_JITTER", "sobol": "SOBOL"}[opts["pattern"]]
    c.light_sampling_threshold = opts["light_threshold"]
    c.seed = opts["seed"]
    c.use_animated_seed = False
    c.time_limit = opts["time_limit"]
    for k in ("max_bounces", "diffuse_bounces", "glossy_bounces", "transmission_bounces",
              "volume_bounces", "transparent_max_bounces"):
        setattr(c, k, opts["max_bounces"])
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.blur_glossy = 0.0
    c.caustics_reflective = True
    c.caustics_refractive = True
    c.film_exposure = 1.0
    c.pixel_filter_type = "BOX"
    c.filter_width = 1.0
    for vl in scene.view_layers:
        vl.cycles.use_denoising = False
    vs = scene.view_settings
    vs.view_transform = "Standard"
    vs.look = "None"
    vs.exposure = 0.0
    vs.gamma = 1.0
    vs.use_curve_mapping = False
    scene.sequencer_colorspace_settings.name = "Linear"
    im = r.image_settings
    im.file_format = "OPEN_EXR"
    im.color_mode = "RGB"
    im.color_depth = "32"
    im.exr_codec = "ZIP"


def write_pfm(exr_path, pfm_path):
    """PFM from the EXR Blender wrote (linear float; PFM rows run bottom-up, as Blender's)."""
    img = bpy.data.images.load(exr_path)
    w, h = img.size
    px = list(img.pixels)
    ch = img.channels
    tmp = pfm_path + ".tmp"
    with open(tmp, "wb") as fh:
        fh.write(b"PF\n%d %d\n-1.0\n" % (w, h))
        rgb = []
        for i in range(w * h):
            rgb.extend(px[i * ch:i * ch + 3])
        fh.write(struct.pack("<%df" % len(rgb), *rgb))
    os.replace(tmp, pfm_path)


def exr_string_attributes(path):
    """The string attributes of an EXR header (Cycles stores its timings there:
    cycles.<layer>.render_time, .synchronization_time). The header is: magic, version,
    then (name NUL, type NUL, int32 size, value) until an empty name."""
    out = {}
    with open(path, "rb") as fh:
        data = fh.read(1 << 16)
    pos = 8
    while pos < len(data) and data[pos] != 0:
        name_end = data.index(b"\0", pos)
        type_end = data.index(b"\0", name_end + 1)
        size = struct.unpack("<i", data[type_end + 1:type_end + 5])[0]
        value = data[type_end + 5:type_end + 5 + size]
        if data[name_end + 1:type_end] == b"string":
            out[data[pos:name_end].decode("ascii", "replace")] = value.decode("ascii", "replace")
        pos = type_end + 5 + size
    return out


def clock_seconds(text):
    """Cycles' "MM:SS.ss" or "HH:MM:SS.ss" as seconds; None if it is neither."""
    try:
        parts = [float(e) for e in text.split(":")]
    except ValueError:
        return None
    secs = 0.0
    for part in parts:
        secs = 60.0 * secs + part
    return secs


def main():
    opts = parse_args(sys.argv)
    try:
        mats, camera, by_mat, lights = read_scene(opts["scene"])
    except SceneError as e:
        fail("%s: %s" % (opts["scene"], e))
    scene = bpy.context.scene
    build(scene, mats, camera, by_mat, lights, opts["spot_model"])
    configure(scene, opts)
    out = os.path.abspath(opts["out"])
    pfm = out.lower().endswith(".pfm")
    exr = out + ".tmp.exr" if pfm else out[:-4] + ".tmp.exr"
    t0 = time.perf_counter()
    bpy.ops.render.render(write_still=False)
    t1 = time.perf_counter()
    res = bpy.data.images["Render Result"]
    res.save_render(exr, scene=scene)
    if not os.path.isfile(exr):
        fail("%s: Blender wrote no image" % exr, 1)
    times = {"render": None, "sync": None}
    try:
        for k, v in exr_string_attributes(exr).items():
            if k.startswith("cycles.") and k.endswith(".render_time"):
                times["render"] = clock_seconds(v)
            elif k.startswith("cycles.") and k.endswith(".synchronization_time"):
                times["sync"] = clock_seconds(v)
    except (ValueError, struct.error):
        pass
    if pfm:
        write_pfm(exr, out)
        os.remove(exr)
    else:
        os.replace(exr, out)
    # One machine-readable line for tools/cycles/measure.sh: Cycles' own sampling time
    # (render_time, 10 ms resolution), its scene synchronisation (BVH build included), and
    # the wall time of the render call around both; none of them counts Blender's start-up
    # or this script's scene building.
    def fmt(v):
        return "%.3f" % v if v is not None else "nan"
    print("cycles_render_seconds=%s cycles_sync_seconds=%s render_call_seconds=%.3f "
          "spp=%d width=%d height=%d seed=%d"
          % (fmt(times["render"]), fmt(times["sync"]), t1 - t0, opts["spp"], opts["width"],
             opts["height"], opts["seed"]))
    sys.stdout.flush()
    os._exit(0)


main()
