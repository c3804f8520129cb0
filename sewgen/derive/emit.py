"""Declaration -> generated files: C kernels, header, cffi cdef and manifest (DESIGN.md §2, §4).

Every C string is computed in :mod:`derive.kernels`; the jinja2 templates (StrictUndefined) only lay it out.
The manifest (names, units, sizes, defaults, layout of the observables) is written as JSON and also
compiled into each mechanism as a string, so a loaded module describes itself.
"""
from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import jinja2

from .. import abi
from . import abi_header, branches, drawing
from .elements import ELEMENTS
from .joints import kind_of
from .dyads import split_into_dyads
from .kernels import KernelSet
from .kinematics import Kinematics
from .kinetostatics import Kinetostatics
from .model import Mechanism
from ..units import to_si

_TEMPLATES = jinja2.Environment(
    loader=jinja2.FileSystemLoader(str(Path(__file__).parent / "templates")),
    undefined=jinja2.StrictUndefined, trim_blocks=True, lstrip_blocks=True, keep_trailing_newline=True,
    autoescape=False)

POINT_FIELDS = ["x", "y", "vx", "vy", "ax", "ay"]
BODY_FIELDS = ["angle", "omega", "alpha"] + [f"com_{f}" for f in POINT_FIELDS]


@dataclass
class Generated:
    name: str
    prefix: str
    c_source: str
    prototypes: list
    manifest: dict


def _force_manifest(kst: Kinetostatics) -> dict:
    reactions, offset = [], 0
    for r in kst.reactions:
        entry = {"name": r.name, "kind": r.kind, "a": r.a.name, "b": r.b.name, "grounded": r.grounded,
                 "columns": r.columns, "offset": offset}
        entry.update(r.joint_kind.manifest(kst.mech, r))  # a drive: the input it turns, its sense
        reactions.append(entry)
        offset += len(r.columns)
    return {
        "reactions": reactions,
        "force_outputs": [{"name": name, "unit": unit} for name, unit, _ in kst.outputs],
        "loads": [{"name": name, "component": comp, "body": body.name} for name, comp, body, _ in kst.load_slots],
        "elements": [{"name": el.name, "kind": el.kind, "bodies": [b.name for b in el.bodies], "doc": el.doc,
                      "outputs": [name for name, _, _ in ELEMENTS[el.kind].outputs(kst, el)]}
                     for el in kst.mech.elements],
        "force_rows": kst.row_names,
        "force_blocks": [len(cols) for _, cols in kst.blocks],
    }


def manifest_of(mech: Mechanism, kin: Kinematics, kst: Kinetostatics, dyads, kernels, sizes: dict,
                blocks: list = (), constants: list = ()) -> dict:
    offset = 0
    points, bodies = [], []
    role = mech.role_of
    for name, att, doc in mech.points:
        points.append({"name": name, "offset": offset, "doc": doc, "body": att.body.name, "role": role("point", name)})
        offset += len(POINT_FIELDS)
    for body in mech.bodies:
        if body.moving:
            entry = {"name": body.name, "kind": body.kind, "offset": offset, "doc": body.doc,
                     "role": role("body", body.name)}
            bodies.append(entry)
            offset += len(BODY_FIELDS)
    return {
        "name": mech.name,
        "doc": mech.doc.strip(),
        "closed_form": dyads is not None,
        "default_speed": to_si(mech.default_speed, "speed", f"{mech.name}.default_speed"),
        "coords": [{"name": c.name, "unit": "rad" if c.kind == "angle" else "m", "guess": c.guess}
                   for c in kin.coords],
        "inputs": [{"name": i.name, "kind": i.kind, "unit": "rad" if i.quantity == "angle" else "m",
                    "default": i.default,
                    "display_unit": i.display_unit, "doc": i.doc, "role": role("input", i.name)}
                   for i in mech.inputs],
        "params": [{"name": p.name, "kind": p.kind, "unit": p.unit, "default": p.default,
                    "display_unit": p.display_unit, "positive": p.positive, "doc": p.doc,
                    "role": role("param", p.name),
                    **{k: v for k, v in (("minimum", p.minimum), ("maximum", p.maximum)) if v is not None}}
                   for p in mech.params],
        "roles": {r: {"kind": kind, "name": name} for r, (kind, name) in sorted(mech.roles.items())},
        "points": points,
        "point_fields": POINT_FIELDS,
        "bodies": bodies,
        "body_fields": BODY_FIELDS,
        "observables": [{"name": o.name, "unit": o.unit} for o in kin.observables],
        "closure": kin.closure_names,
        "branches": [{"joint": d.joint.name, "kind": d.kind, "default": d.joint.branch, "meaning": d.meaning}
                     for d in (dyads or [])],
        "blocks": [{"joints": b.joints, "rows": b.rows, "coords": b.cols} for b in blocks],
        "constants": constants,
        "kernels": {k.name: {"ops": k.ops} for k in kernels},
        "sizes": sizes,
        **_force_manifest(kst),
    }


def observable_groups(mech: Mechanism, kin: Kinematics) -> list[int]:
    """Where each group of observables starts (and, last, their number): each point's POINT_FIELDS, each moving
    body's BODY_FIELDS, each cam's arc index, each spatial crank's centre-of-mass z (z, z_d, z_dd), in the
    manifest's order (kinematics._derive_observables). A sweep that keeps a few outputs computes only their groups
    (kernel 'observe')."""
    sizes = ([len(POINT_FIELDS)] * len(mech.points) + [len(BODY_FIELDS)] * sum(b.moving for b in mech.bodies)
             + [1] * len(kin.cams) + [3] * len(kin.spatial_bodies))
    starts = [0]
    for k in sizes:
        starts.append(starts[-1] + k)
    if starts[-1] != len(kin.observables):
        raise AssertionError(f"{mech.name}: observable groups cover {starts[-1]} of {len(kin.observables)}")
    return starts


def _c_string_chunks(text: str, width: int = 96) -> list[str]:
    esc = text.replace("\\", "\\\\").replace('"', '\\"').replace("?", "\\?")  # \? : no trigraphs
    chunks = []
    while esc:
        cut = min(width, len(esc))
        while cut < len(esc) and esc[cut - 1] == "\\":  # never split an escape
            cut += 1
        chunks.append(esc[:cut])
        esc = esc[cut:]
    return chunks


def generate(mech: Mechanism, closed_form: bool = True) -> Generated:
    """Derive one mechanism and render its C file and manifest."""
    kin = Kinematics(mech)
    dyads = split_into_dyads(kin) if closed_form else None
    prefix = f"sg_{mech.name}"
    ks = KernelSet(prefix, kin)
    kst = Kinetostatics(kin)
    anchor_list, arc_list = drawing.anchors(kin, kind_of)
    anchor_out = drawing.outputs(anchor_list, arc_list)
    blks = branches.blocks(kin)
    groups = observable_groups(mech, kin)
    row_scales = branches.row_scales(kin)
    if dyads is None:  # Newton: the rates, their SIMD twins and Newton's LU factor Φ_q by its blocks
        ks.solve_by_blocks(blks)
    kernels = ([ks.closed(dyads)] if dyads is not None else []) + [
        ks.residual(), *ks.lu(), ks.scales(row_scales), ks.blocks(blks), ks.motion(row_scales),
        ks.rates(row_scales), ks.observe(groups, row_scales), ks.forces(kst),
        ks.force_matrix(kst), ks.anchors(anchor_out)]
    vector_kernels = ks.vector_kernels(dyads, row_scales, kst, groups, blks)
    kernels.insert(0, ks.constants_kernel())  # last to build: it evaluates what the others hoisted
    sizes = {"nq": len(kin.q), "nx": len(kin.x), "np": len(kin.p), "nobs": len(kin.observables),
             "nbranch": len(dyads or []), "nc": len(ks.constants), "nf": len(kst.f),
             "nfo": len(kst.f) + len(kst.outputs), "nload": len(kst.load_slots), "nanchor_out": len(anchor_out),
             "nblock": len(blks), "ngroup": len(groups) - 1}
    index = {sym: i for i, sym in enumerate(kin.p)}  # the parameters each hoisted constant reads
    constants = [sorted(index[s] for s in e.free_symbols if s in index) for e in ks.constants]
    manifest = manifest_of(mech, kin, kst, dyads, kernels, sizes, blks, constants)
    manifest.update(drawing.manifest(anchor_list, arc_list))
    text = json.dumps(manifest, sort_keys=True, separators=(",", ":"), ensure_ascii=True)
    c_source = _TEMPLATES.get_template("mechanism.c.j2").render(
        mech={"name": mech.name,
              "title": (mech.doc.strip().splitlines() or [mech.name])[0].replace("*/", "* /").replace("??", "? ?"),
              "coord_names": ", ".join(c.name for c in kin.coords) or "none",
              "input_names": ", ".join(i.name for i in mech.inputs)},
        prefix=prefix, kernels=kernels,
        inline_sweep=abi.kernel_hook("sweep", f"{prefix}_sweep") if dyads is not None else None,
        vector_kernels=vector_kernels, nobs=len(kin.observables), nfo=len(kst.f) + len(kst.outputs),
        forces_v=(f"{prefix}_forces_v" if any(k.name == f"{prefix}_forces_v" for k in vector_kernels)
                  else "sgv_no_forces"),
        simd_sweep=(abi.kernel_hook("sweep_simd", f"{prefix}_sweep_simd")
                    if vector_kernels and dyads is not None else None),
        simd_finish=(abi.kernel_hook("finish_simd", f"{prefix}_finish_simd")
                     if vector_kernels and dyads is None else None),
        simd_newton=(abi.kernel_hook("newton_simd", f"{prefix}_newton_simd")
                     if any(k.name == f"{prefix}_residual_v" for k in vector_kernels) else None),
        nq=len(kin.q),
        angle_flags=[1 if c.kind == "angle" else 0 for c in kin.coords],
        group_start=groups, group_always=ks.observe_always(groups, row_scales),
        group_angles=ks.angle_readers(groups, row_scales),
        descriptor=abi_header.descriptor_initializer(prefix, sizes, {k.name[len(prefix) + 1:]: True for k in kernels + vector_kernels}),
        manifest_chunks=_c_string_chunks(text))
    prototypes = [k.prototype for k in kernels] + [
        f"const sg_mechanism *{prefix}(void);", f"const char *{prefix}_manifest(void);"]
    return Generated(mech.name, prefix, c_source, prototypes, manifest)


def render_files(generated: list[Generated], header: str = "sg_kernels.h") -> dict[str, str]:
    """All files of one compiled module: sg_<name>.c per mechanism, the kernels' header and cdef, the runtime's
    ABI header and cdef (sewgen/abi.py), manifest.json."""
    files = {f"{g.prefix}.c": g.c_source for g in generated}
    mechs = [{"name": g.name, "prototypes": g.prototypes} for g in generated]
    guard = header.upper().replace(".", "_").replace("-", "_")
    files[header] = _TEMPLATES.get_template("kernels.h.j2").render(mechanisms=mechs, guard=guard)
    files["sg_kernels.cdef"] = _TEMPLATES.get_template("kernels.cdef.j2").render(mechanisms=mechs)
    files["sg_abi.h"], files["sg_abi.cdef"] = abi_header.header(), abi_header.cdef()
    files["manifest.json"] = json.dumps({g.name: g.manifest for g in generated}, indent=1, sort_keys=True,
                                        ensure_ascii=False) + "\n"
    return files
