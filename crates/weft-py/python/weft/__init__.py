"""weft for Python: learned garment deformation on moving bodies.

Bodies posed by SMPL parameters, motions (AMASS ``.npz``, BVH, procedural), procedural
garments with their sewing-pattern UVs, weft's cloth simulator, datasets, trained models
animating any garment, and the renderer, with numpy arrays in and out.

Conventions everywhere: metres, seconds, Y up; positions ``float32`` ``(N, 3)`` or
``(T, N, 3)``, triangles ``uint32`` ``(F, 3)``, poses ``float32`` ``(T, 24, 3)``
axis-angle in SMPL's joint order. Bad input raises ``ValueError`` (``OSError`` for
files) with weft's message, which names the file and the field.

Example::

    import weft
    body = weft.Body()
    walk = weft.procedural_motion("walk", frames=30)
    skirt = weft.generate_garment("skirt", vertices=1000)
    frames, stats = weft.simulate(skirt, walk, material="silk")
    picture = weft.render([(frames[-1], skirt.faces), (body.pose(walk.poses, walk.trans)[-1], body.faces)])
"""

from ._weft import (
    Body,
    Dataset,
    Garment,
    Motion,
    Run,
    __version__,
    generate_garment,
    import_dataset,
    load_garment,
    load_motion,
    procedural_motion,
    render,
    simulate,
)

__all__ = [
    "Body",
    "Dataset",
    "Garment",
    "Motion",
    "Run",
    "__version__",
    "generate_garment",
    "import_dataset",
    "load_garment",
    "load_motion",
    "procedural_motion",
    "render",
    "simulate",
]
