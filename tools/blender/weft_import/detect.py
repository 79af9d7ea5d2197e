"""What a weft output directory holds and how to import it: pure Python, no bpy.

`plan(path, method)` looks at a directory (or one file) and returns a `Plan`: which
importer to run on which file, the frame rate and where it came from, the frame count.
Every problem is a `WeftImportError` whose message names the file and what was expected;
nothing here raises anything else for a bad or unexpected file.

Layouts recognised (see docs/blender.md, "The weft_import add-on"):

- `weft simulate --out DIR`: frames.pc2, frames.npy, stats.json (with "fps"),
  obj/frame_00000.obj with --obj, scene.usda (garment and body) with --usd;
- `weft demo`'s animation/ directory: garment.obj, garment.pc2, animation.glb;
- anything `weft export` / `weft animate` wrote: a .glb/.gltf, a .usda/.usd, or a
  .pc2/.mdd point cache beside the template OBJ (same stem, or the only OBJ there).
"""

import json
import math
import os
import re
import struct

#: The import routes, in the order AUTO tries them.
METHODS = ("GLTF", "USD", "MESH_CACHE")

GLTF_EXT = (".glb", ".gltf")
USD_EXT = (".usda", ".usd", ".usdc", ".usdz")
CACHE_EXT = (".pc2", ".mdd")
MESH_EXT = (".obj", ".ply")


class WeftImportError(Exception):
    """A weft output that cannot be imported; the message names the file and says why."""


class Plan:
    """What to import and how. `method` is one of METHODS."""

    def __init__(self, directory, layout, method, source):
        self.directory = directory  # the directory the output lives in
        self.layout = layout  # "simulate", "demo" or "export"
        self.method = method
        self.source = source  # the .glb/.usd file, or the point cache
        self.mesh = None  # MESH_CACHE: the rest mesh the cache applies to
        self.cache_format = None  # MESH_CACHE: "PC2" or "MDD"
        self.points = None  # MESH_CACHE: vertices in the cache
        self.fps = None  # frames per second, when some file records it
        self.fps_source = None  # the file it came from
        self.frames = None  # frame count, when known before importing
        self.start = 0.0  # USD: the stage's startTimeCode
        self.mesh_names = []  # GLTF: the names of the nodes that hold meshes
        self.alternatives = []  # other routes this directory offers
        self.notes = []

    def __repr__(self):
        return "Plan(%s)" % ", ".join("%s=%r" % kv for kv in sorted(vars(self).items()))


# --- reading headers -------------------------------------------------------------------


def _read_head(path, size):
    try:
        with open(path, "rb") as f:
            return f.read(size)
    except OSError as e:
        raise WeftImportError("%s: cannot be read (%s)" % (path, e.strerror or e)) from None


def _file_size(path):
    try:
        return os.path.getsize(path)
    except OSError as e:
        raise WeftImportError("%s: cannot be read (%s)" % (path, e.strerror or e)) from None


def pc2_header(path):
    """(points, samples) of a PC2 point cache, checked against the file's size."""
    head = _read_head(path, 32)
    if len(head) < 32 or head[:12] != b"POINTCACHE2\0":
        raise WeftImportError(
            "%s: not a PC2 point cache (expected the 'POINTCACHE2' header of 32 bytes)" % path
        )
    _version, points, _start, _rate, samples = struct.unpack("<iiffi", head[12:32])
    if points <= 0 or samples <= 0:
        raise WeftImportError(
            "%s: PC2 header says %d points and %d samples; expected both positive"
            % (path, points, samples)
        )
    expected = 32 + points * samples * 12
    size = _file_size(path)
    if size != expected:
        raise WeftImportError(
            "%s: %d bytes, but its header (%d points x %d samples) needs %d; the file is "
            "truncated or not a PC2 cache" % (path, size, points, samples, expected)
        )
    return points, samples


def mdd_header(path):
    """(points, frames, frame times) of an MDD point cache (big-endian, weft's layout)."""
    head = _read_head(path, 8)
    if len(head) < 8:
        raise WeftImportError("%s: too short for an MDD header (8 bytes)" % path)
    frames, points = struct.unpack(">ii", head)
    if points <= 0 or frames <= 0:
        raise WeftImportError(
            "%s: MDD header says %d frames of %d points; expected both positive"
            % (path, frames, points)
        )
    expected = 8 + frames * 4 + frames * points * 12
    size = _file_size(path)
    if size != expected:
        raise WeftImportError(
            "%s: %d bytes, but its header (%d frames x %d points) needs %d; the file is "
            "truncated, not an MDD cache, or has the extra rest frame Blender's own MDD "
            "exporter writes" % (path, size, frames, points, expected)
        )
    raw = _read_head(path, 8 + frames * 4)[8:]
    times = list(struct.unpack(">%df" % frames, raw))
    return points, frames, times


def gltf_json(path):
    """The JSON document of a .glb (its first chunk) or a .gltf file."""
    if path.lower().endswith(".gltf"):
        try:
            with open(path, "rb") as f:
                return json.loads(f.read().decode("utf-8"))
        except OSError as e:
            raise WeftImportError("%s: cannot be read (%s)" % (path, e.strerror or e)) from None
        except ValueError as e:
            raise WeftImportError("%s: not valid glTF JSON (%s)" % (path, e)) from None
    head = _read_head(path, 20)
    if len(head) < 20 or head[:4] != b"glTF":
        raise WeftImportError("%s: not a glTF binary (expected the 'glTF' magic)" % path)
    version, length, chunk_len, chunk_type = struct.unpack("<IIII", head[4:20])
    if version != 2:
        raise WeftImportError("%s: glTF version %d; expected 2" % (path, version))
    if chunk_type != 0x4E4F534A or 20 + chunk_len > length:
        raise WeftImportError("%s: the first chunk is not the glTF JSON chunk" % path)
    raw = _read_head(path, 20 + chunk_len)[20:]
    try:
        return json.loads(raw.decode("utf-8"))
    except ValueError as e:
        raise WeftImportError("%s: its JSON chunk does not parse (%s)" % (path, e)) from None


def gltf_timing(path):
    """(fps, frames, mesh node names) of a glTF file. weft's key times are k / fps; the rate
    is (keys - 1) / (last time - first time) over the longest sampler. (None, 1, names)
    for a file without animation."""
    doc = gltf_json(path)
    accessors = doc.get("accessors") or []
    keys, span = 0, 0.0
    for anim in doc.get("animations") or []:
        for sampler in anim.get("samplers") or []:
            try:
                acc = accessors[sampler["input"]]
                count = int(acc["count"])
                lo, hi = float(acc["min"][0]), float(acc["max"][0])
            except (KeyError, IndexError, TypeError, ValueError):
                continue
            if count > keys:
                keys, span = count, hi - lo
    names = [
        n.get("name") or "mesh_%d" % i
        for i, n in enumerate(doc.get("nodes") or [])
        if "mesh" in n
    ]
    if keys < 2 or not span > 0:
        return None, max(keys, 1), names
    return (keys - 1) / span, keys, names


_USD_META = re.compile(
    r"\b(timeCodesPerSecond|framesPerSecond|startTimeCode|endTimeCode)\s*=\s*"
    r"([-+]?[0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)"
)


def usd_timing(path):
    """The stage metadata of a text USD layer: {'timeCodesPerSecond': ..., ...} as read
    from its header, or None for a binary (crate, usdz) file."""
    head = _read_head(path, 1 << 16)
    if not head.startswith(b"#usda"):
        return None
    text = head.decode("utf-8", "replace")
    # The layer's metadata is the first parenthesised block after the '#usda' line.
    body = text.split("\n", 1)[1] if "\n" in text else ""
    m = re.match(r"\s*\((.*?)\n\)", body, re.S)
    block = m.group(1) if m else ""
    return {k: float(v) for k, v in _USD_META.findall(block)}


def read_stats(path):
    """stats.json of `weft simulate`: (fps, frames or None, the garment path recorded)."""
    try:
        with open(path, "rb") as f:
            stats = json.loads(f.read().decode("utf-8"))
    except OSError as e:
        raise WeftImportError("%s: cannot be read (%s)" % (path, e.strerror or e)) from None
    except ValueError as e:
        raise WeftImportError("%s: not valid JSON (%s)" % (path, e)) from None
    if not isinstance(stats, dict):
        raise WeftImportError("%s: expected a JSON object (weft simulate's stats)" % path)
    fps = stats.get("fps")
    if isinstance(fps, bool) or not isinstance(fps, (int, float)) or not (
        math.isfinite(fps) and fps > 0
    ):
        raise WeftImportError(
            "%s: \"fps\" is %r; expected a positive number (weft simulate writes it)"
            % (path, fps)
        )
    frames = None
    if isinstance(stats.get("frames"), list):
        frames = len(stats["frames"])
    elif isinstance(stats.get("totals"), dict) and isinstance(
        stats["totals"].get("frames"), int
    ):
        frames = stats["totals"]["frames"]
    garment = stats.get("garment") if isinstance(stats.get("garment"), str) else None
    return float(fps), frames, garment


def mesh_vertex_count(path):
    """Vertices of an OBJ (its `v` lines) or a PLY (its `element vertex` line)."""
    try:
        if path.lower().endswith(".ply"):
            with open(path, "rb") as f:
                for _ in range(64):
                    line = f.readline()
                    if line.startswith(b"element vertex"):
                        return int(line.split()[2])
                    if not line or line.startswith(b"end_header"):
                        break
            raise WeftImportError("%s: no 'element vertex' line in the PLY header" % path)
        n = 0
        with open(path, "rb") as f:
            for line in f:
                if line.startswith(b"v ") or line.startswith(b"v\t"):
                    n += 1
        return n
    except OSError as e:
        raise WeftImportError("%s: cannot be read (%s)" % (path, e.strerror or e)) from None
    except (ValueError, IndexError):
        raise WeftImportError("%s: its PLY header does not parse" % path) from None


# --- choosing what to import -----------------------------------------------------------


def _listing(directory):
    try:
        names = sorted(os.listdir(directory))
    except OSError as e:
        raise WeftImportError("%s: cannot be listed (%s)" % (directory, e.strerror or e)) from None
    return [n for n in names if os.path.isfile(os.path.join(directory, n))]


def _with_ext(names, exts):
    return [n for n in names if n.lower().endswith(exts)]


def _pick(directory, names, preferred, what):
    """One file of `names`: the first of `preferred` present, the only one, or an error
    listing them."""
    for p in preferred:
        if p in names:
            return os.path.join(directory, p)
    if len(names) == 1:
        return os.path.join(directory, names[0])
    if not names:
        return None
    raise WeftImportError(
        "%s: holds %d %s files (%s); import one of them by passing its path"
        % (directory, len(names), what, ", ".join(names))
    )


def _cache_mesh(directory, names, cache, stats_garment):
    """The rest meshes a point cache may apply to, in order: obj/frame_00000.obj of a
    simulate output, a mesh with the cache's stem, the garment stats.json records, the
    only OBJ/PLY there. The caller keeps the first with the cache's vertex count."""
    stem = os.path.splitext(os.path.basename(cache))[0]
    candidates = [os.path.join(directory, "obj", "frame_00000.obj")]
    candidates += [os.path.join(directory, stem + ext) for ext in MESH_EXT]
    if stats_garment:
        g = os.path.expanduser(stats_garment)
        if os.path.isabs(g):
            candidates.append(g)
        else:
            # Relative to where weft ran: often the directory's parent (`weft simulate
            # --garment G.obj --out sim`), else the current directory.
            candidates += [os.path.join(os.path.dirname(directory), g), os.path.abspath(g)]
    meshes = _with_ext(names, MESH_EXT)
    if len(meshes) == 1:
        candidates.append(os.path.join(directory, meshes[0]))
    seen = []
    for c in map(os.path.normpath, candidates):
        if c not in seen and os.path.isfile(c):
            seen.append(c)
    return seen


def tidy_rate(fps):
    """A rate read from float32 data (glTF key times, USD written from an f32) back to the
    decimal it was typed as: 29.969999313 -> 29.97, 23.97600001 -> 23.976."""
    short = round(fps, 3)
    return short if short > 0 and abs(fps - short) <= 1e-6 * fps else fps


def _set_fps(p, fps, source):
    if p.fps is None and fps is not None:
        p.fps, p.fps_source = tidy_rate(float(fps)), source


def plan(path, method="AUTO"):
    """How to import `path` (a weft output directory, or one .glb/.gltf/.usd*/.pc2/.mdd
    file) with `method` ("AUTO" or one of METHODS)."""
    method = (method or "AUTO").upper()
    if method != "AUTO" and method not in METHODS:
        raise WeftImportError(
            "method %r: expected AUTO, %s" % (method, ", ".join(METHODS))
        )
    path = os.path.abspath(os.path.expanduser(os.fspath(path)))
    if os.path.isdir(path):
        directory, names, only = path, _listing(path), None
    elif os.path.isfile(path):
        directory = os.path.dirname(path)
        names, only = _listing(directory), os.path.basename(path)
    else:
        raise WeftImportError("%s: no such file or directory" % path)

    stats_path = os.path.join(directory, "stats.json")
    stats = read_stats(stats_path) if "stats.json" in names else None
    if stats is not None and "frames.pc2" in names:
        layout = "simulate"
    elif "animation.glb" in names and "garment.pc2" in names:
        layout = "demo"
    else:
        layout = "export"

    def restrict(found):
        return [n for n in found if n == only] if only else found

    glbs = restrict(_with_ext(names, GLTF_EXT))
    usds = restrict(_with_ext(names, USD_EXT))
    caches = restrict(_with_ext(names, CACHE_EXT))
    if only and not (glbs or usds or caches):
        raise WeftImportError(
            "%s: not a file weft_import reads (expected .glb, .gltf, .usda, .usd, .usdc, "
            ".usdz, .pc2 or .mdd, or a weft output directory)" % path
        )

    routes = {}
    if glbs:
        routes["GLTF"] = lambda: _pick(directory, glbs, ["animation.glb", "scene.glb"], "glTF")
    if usds:
        routes["USD"] = lambda: _pick(directory, usds, ["scene.usda"], "USD")
    if caches:
        routes["MESH_CACHE"] = lambda: _pick(
            directory, caches, ["frames.pc2", "garment.pc2"], "point cache"
        )
    if not routes:
        found = ", ".join(names[:12]) + (", ..." if len(names) > 12 else "") or "no files"
        raise WeftImportError(
            "%s: nothing to import: expected a weft output (weft simulate's frames.pc2 and "
            "stats.json, weft demo's animation.glb, or an exported .glb, .usda or .pc2/.mdd "
            "beside its OBJ); found %s" % (directory, found)
        )
    if method == "AUTO":
        chosen = next(m for m in METHODS if m in routes)
    elif method in routes:
        chosen = method
    else:
        raise WeftImportError(
            "%s: holds nothing for the %s route (%s); it offers %s"
            % (
                path,
                method,
                {
                    "GLTF": "no .glb or .gltf",
                    "USD": "no .usda, .usd, .usdc or .usdz",
                    "MESH_CACHE": "no .pc2 or .mdd",
                }[method],
                ", ".join(routes),
            )
        )
    source = routes[chosen]()
    p = Plan(directory, layout, chosen, source)
    p.alternatives = [m for m in routes if m != chosen]
    if stats is not None:
        _set_fps(p, stats[0], stats_path)

    if chosen == "GLTF":
        fps, frames, p.mesh_names = gltf_timing(source)
        _set_fps(p, fps, source)
        p.frames = frames
    elif chosen == "USD":
        meta = usd_timing(source)
        if meta is None:
            p.notes.append(
                "%s is a binary USD file: its frame rate is not read (Blender's USD "
                "importer does not set it)" % os.path.basename(source)
            )
        else:
            # USD's defaults when the layer says nothing: 24 time codes per second.
            tcps = meta.get("timeCodesPerSecond", meta.get("framesPerSecond", 24.0))
            _set_fps(p, tcps if tcps > 0 else None, source)
            p.start = meta.get("startTimeCode", 0.0)
            if "endTimeCode" in meta:
                p.frames = int(round(meta["endTimeCode"] - p.start)) + 1
    else:
        if source.lower().endswith(".mdd"):
            p.cache_format = "MDD"
            p.points, p.frames, times = mdd_header(source)
            if p.frames > 1 and times[-1] > times[0]:
                _set_fps(p, (p.frames - 1) / (times[-1] - times[0]), source)
        else:
            p.cache_format = "PC2"
            p.points, p.frames = pc2_header(source)
        meshes = _cache_mesh(directory, names, source, stats[2] if stats else None)
        if not meshes:
            raise WeftImportError(
                "%s: no mesh for this point cache: expected obj/frame_00000.obj, %s.obj "
                "beside it%s, or one OBJ in %s"
                % (
                    source,
                    os.path.splitext(os.path.basename(source))[0],
                    ", the garment stats.json records (%s)" % stats[2] if stats and stats[2] else "",
                    directory,
                )
            )
        counts = []
        for m in meshes:
            n = mesh_vertex_count(m)
            if n == p.points:
                p.mesh = m
                break
            counts.append("%s has %d" % (m, n))
        if p.mesh is None:
            raise WeftImportError(
                "%s: the cache moves %d vertices, but %s; the cache belongs to another mesh"
                % (source, p.points, "; ".join(counts))
            )
        if p.fps is None:
            # PC2 records no rate: take it from another file of the same output.
            others = _with_ext(names, GLTF_EXT) + _with_ext(names, USD_EXT)
            for other in others:
                full = os.path.join(directory, other)
                try:
                    if other.lower().endswith(GLTF_EXT):
                        fps = gltf_timing(full)[0]
                    else:
                        meta = usd_timing(full) or {}
                        fps = meta.get("timeCodesPerSecond", meta.get("framesPerSecond"))
                except WeftImportError:
                    continue
                if fps:
                    _set_fps(p, fps, full)
                    break
        if p.fps is None:
            p.notes.append(
                "%s records no frame rate (PC2 holds none) and nothing beside it does: "
                "the scene's rate is kept" % os.path.basename(source)
            )
    if stats is not None and stats[1] is not None and p.frames is not None and stats[1] != p.frames:
        p.notes.append(
            "stats.json lists %d frames, %s holds %d" % (stats[1], os.path.basename(source), p.frames)
        )
    return p


def scene_rate(fps):
    """(render.fps, render.fps_base) for a rate that may not be an integer: Blender's
    rate is fps / fps_base with an integer fps."""
    if not (isinstance(fps, (int, float)) and math.isfinite(fps) and 0 < fps <= 32767):
        raise WeftImportError("frame rate %r: expected a positive number up to 32767" % fps)
    whole = max(1, int(round(fps)))
    # Within float32 rounding of an integer rate (glTF key times are float32): that integer.
    if abs(fps - whole) <= 1e-5 * whole:
        return whole, 1.0
    return whole, whole / fps
