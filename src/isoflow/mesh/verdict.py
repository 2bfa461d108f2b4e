"""A genus verdict as data (:class:`GenusVerdict`), and its words.

:func:`isoflow.mesh.genus.verify_genus` decides; this module holds what it
decides (the kind of verdict, the facts it rests on, why the resolution
stepping stopped, the notes) and the one wording of it that the command
line and :meth:`GenusVerdict.to_dict` share. A limit that stopped the
stepping is named by the :func:`~isoflow.mesh.genus.verify_genus` parameter
that sets it (``max_resolution``, ``time_limit``), as data; its words write
it as the command line's option.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

from ..errors import IsoflowError, counted
from ..results import Result
from ..scale.memory import sized
from .fills import Fill
from .grid import rounding_words

#: what the verdict says, first
VerdictKind = Literal["agree", "disagree", "not_converged", "self_intersecting", "no_solid", "no_reference"]
#: why the resolution stepping stopped before the Betti numbers settled
StopKind = Literal["asked", "max_resolution", "time_limit", "memory", "no_inside", "touching"]
#: the facts said after the verdict
NoteKind = Literal["dropped_faces", "welded", "repeated_faces", "double_sided", "open", "inconsistent",
                   "nonmanifold_edges", "nonmanifold_vertices", "nested", "overlap", "self_intersecting",
                   "zero_area_faces", "float64_rounding", "cavities", "flood_cavities", "coarse", "manifold3d_refused",
                   "no_mesh_genus", "t_junctions", "corner_joins", "body_count", "thin_overlap", "voxel_contacts",
                   "written_connectivity"]


@dataclass(frozen=True)
class Stop:
    """Why :func:`~isoflow.mesh.genus.digital_steps` stopped stepping.

    ``limit`` is the value of the limit (a resolution, seconds), ``option``
    the parameter that sets it, ``resolution`` the next resolution (not
    tried) and ``estimate`` what it would have taken (seconds for
    ``time_limit``, bytes for ``memory``). An ``asked`` stop has a
    ``limit`` where the resolutions asked pass ``max_resolution`` (which
    caps only the doubling; ``resolution`` is then the last one asked).
    A ``no_inside`` stop ends the stepping after the resolutions asked
    where a non-orientable component leaves nothing to compare with: no
    finer grid settles what its winding number reads. A ``touching`` stop
    ends it at ``resolution``, the last tried, where the voxels join solids
    that touch at a point or along an edge (26-connected ones, or a flood
    fill's shell) and the last two grids read the solid so joined: no finer
    grid parts them.
    """

    kind: StopKind
    limit: float | None = None
    resolution: int | None = None
    estimate: float | None = None
    option: str | None = None


@dataclass(frozen=True)
class Note:
    """One fact said after the verdict: its kind and its figures."""

    kind: NoteKind
    facts: Mapping[str, Any] = field(default_factory=dict)


@dataclass(frozen=True, eq=False, repr=False)
class GenusVerdict(Result):
    """What :func:`~isoflow.mesh.genus.verify_genus` found, as fields and as
    a mapping of the keys ``isoflow genus --json`` prints (``v.agree``,
    ``v["agree"]``); :meth:`~GenusVerdict.to_dict` is that JSON object.

    ``reference`` is the genus the digital genus is compared with, taken
    from ``reference_source`` (``"mesh"``: the mesh's own genus; ``"solid"``:
    the genus of the solid manifold3d builds, where components overlap,
    touch or nest; ``"voxels"``: b1 of the voxels a voxel surface that
    touches itself bounds at its own grid, at the digital rows'
    connectivity, its b0 being ``bodies``). ``bodies`` is the number of bodies the digital
    components (b0) are compared with: the solid's (None where not
    compared: no solid, ``fill="shell"``; for a flood fill of a solid with
    cavities, the filled solid's); a verdict with other digital components
    is ``disagree``. ``filled_genus`` is, for ``fill="flood"`` of a solid
    with cavities, the genus of the solid with its cavities filled (what
    the flood fill voxelises, without the handles inside the cavities):
    the digital genus is compared with it instead of ``reference``, which
    stays the mesh's (or the solid's); None otherwise.

    Examples
    --------
    >>> from isoflow import data
    >>> from isoflow.mesh.genus import verify_genus
    >>> v = verify_genus(data.torus(), resolutions=[16, 32])
    >>> v.kind, v.reference, v["agree"], [d["betti"] for d in v.digital]
    ('agree', 1, True, [[1, 1, 0], [1, 1, 0]])
    """

    input: str
    mesh: dict
    manifold3d: dict
    pymeshlab: dict
    self_intersecting_faces: int | None
    faces_crossing_other_components: int | None
    solid_genus: int | None
    fill: Fill
    digital: list
    solid: dict
    converged: bool
    agree: bool
    kind: VerdictKind
    reference: int | None
    reference_source: Literal["mesh", "solid", "voxels"]
    stop: Stop | None = None
    notes: tuple[Note, ...] = ()
    bodies: int | None = None
    filled_genus: int | None = None

    #: the keys of the mapping and of :meth:`to_dict`, in the JSON's order:
    #: the sentence, then the facts it is written from, so that a script
    #: reads ``kind`` rather than parsing words, and :meth:`from_dict` takes
    #: the JSON back
    KEYS = ("input", "mesh", "manifold3d", "pymeshlab", "self_intersecting_faces",
            "faces_crossing_other_components", "solid_genus", "fill", "digital", "solid", "converged", "agree", "verdict",
            "kind", "reference", "reference_source", "filled_genus", "bodies", "stop", "notes")

    @property
    def verdict(self) -> str:
        """The verdict in words (:func:`verdict_text`)."""
        return verdict_text(self)

    def _keys(self) -> list[str]:
        # the JSON's keys: the verdict's words are a property
        return list(self.KEYS)

    @classmethod
    def from_dict(cls, values: Mapping[str, Any]) -> GenusVerdict:
        """The verdict of :meth:`to_dict`'s JSON (``isoflow genus --json``):
        the sentence is dropped (it is written again from the facts), the
        stop and the notes are rebuilt from their objects.

        Examples
        --------
        >>> import json
        >>> from isoflow.mesh.genus import verify_genus
        >>> v = verify_genus("meshes/torus.obj", (16, 32))
        >>> back = GenusVerdict.from_dict(json.loads(json.dumps(v.to_dict())))
        >>> back.kind, back.verdict == v.verdict, back.to_dict() == v.to_dict()
        ('agree', True, True)
        """
        given = {k: v for k, v in values.items() if k != "verdict"}
        stop = given.get("stop")
        if isinstance(stop, Mapping):
            given["stop"] = Stop(**stop)
        given["notes"] = tuple(n if isinstance(n, Note) else Note(n["kind"], n.get("facts", {}))
                               for n in given.get("notes", ()))
        return super().from_dict(given)


# --------------------------------------------------------------------------
# words
# --------------------------------------------------------------------------


def option_flag(option: str) -> str:
    """The command line's spelling of a parameter.

    Examples
    --------
    >>> option_flag("time_limit")
    '--time-limit'
    """
    return "--" + option.replace("_", "-")


def stop_text(stop: Stop) -> str:
    """Why the stepping stopped, as the verdict says it.

    Examples
    --------
    >>> stop_text(Stop("max_resolution", limit=256, resolution=512, option="max_resolution"))
    'the largest resolution allowed (256, --max-resolution)'
    >>> stop_text(Stop("asked", limit=64, resolution=256, option="max_resolution"))
    'the resolutions asked (256 is past --max-resolution 64, which caps only the doubling)'
    >>> stop_text(Stop("time_limit", limit=0.5, resolution=512, estimate=0.456, option="time_limit"))
    'the time limit (0.5 s, --time-limit): 512 would end past it (about 0.46 s more)'
    >>> stop_text(Stop("no_inside"))
    'the resolutions asked: a non-orientable component has no inside, so no finer grid settles the digital rows'
    >>> stop_text(Stop("touching", resolution=128))
    'the solids touching at a point or along an edge, which the voxels join at any resolution (at 128)'
    """
    flag = option_flag(stop.option) if stop.option else ""
    if stop.kind == "asked":
        if stop.limit is not None:  # asked beyond the cap: the cap did not stop anything asked
            return f"the resolutions asked ({stop.resolution} is past {flag} {stop.limit}, which caps only the doubling)"
        return "the resolutions asked"
    if stop.kind == "no_inside":
        return "the resolutions asked: a non-orientable component has no inside, so no finer grid settles the digital rows"
    if stop.kind == "touching":
        return f"the solids touching at a point or along an edge, which the voxels join at any resolution (at {stop.resolution})"
    if stop.kind == "max_resolution":
        return f"the largest resolution allowed ({stop.limit}, {flag})"
    if stop.kind == "time_limit":
        # the run stops where the time spent plus this estimate passes the
        # limit, so the estimate alone may be below the limit: the sentence
        # says the next grid would end past it, and gives a short estimate
        # two digits so that it never reads as none at all
        est = stop.estimate or 0.0
        more = f"{est:.0f}" if est >= 10 else f"{est:.2g}"
        return f"the time limit ({stop.limit:g} s, {flag}): {stop.resolution} would end past it (about {more} s more)"
    return f"the memory budget: {stop.resolution} would need about {sized(int(stop.estimate or 0))}"


def verdict_text(v: GenusVerdict) -> str:
    """The verdict sentence: what it says first, then the notes."""
    notes = [note_text(n) for n in v.notes]
    return head_text(v) + ("; " + "; ".join(notes) if notes else "")


def touching_text(mesh: Mapping[str, Any], resolution: int | None, connectivity: int = 26) -> str:
    """Why the stepping stopped at ``resolution`` where the solids touch
    (a Stop "touching"), with where the ``mesh`` row shows them touching;
    at ``connectivity`` 6 the voxels that join them are a flood fill's.

    Examples
    --------
    >>> touching_text({"nonmanifold_edges": 4, "nonmanifold_vertices": 0, "shared_vertices": 0}, 128)
    'stopped at 128: the solids touch along 4 edges, which 26-connected voxels join at any resolution'
    >>> touching_text({"nonmanifold_edges": 0, "nonmanifold_vertices": 0, "shared_vertices": 3}, 64, 6)
    "stopped at 64: the solids touch at 3 vertices, which a flood fill's shell voxels join at any resolution"
    """
    edges, points = mesh.get("nonmanifold_edges", 0), mesh.get("nonmanifold_vertices", 0)
    if not edges and not points:
        points = mesh.get("shared_vertices", 0)
    where = " and ".join(([f"along {counted(edges, 'edge')}"] if edges else [])
                         + ([f"at {counted(points, 'vertex', 'vertices')}"] if points else [])) or "at a point or along an edge"
    voxels = "26-connected voxels" if connectivity == 26 else "a flood fill's shell voxels"
    return f"stopped at {resolution}: the solids touch {where}, which {voxels} join at any resolution"


def head_text(v: GenusVerdict) -> str:
    """What the verdict says first."""
    digital, stop = v.digital, (f"; stopped by {stop_text(v.stop)}" if v.stop else "")
    if v.stop is not None and v.stop.kind == "touching":  # not a limit: the clause says where it stopped and why
        stop = "; " + touching_text(v.mesh, v.stop.resolution, digital[-1]["connectivity"] if digital else 26)
    ref_name = "voxel genus" if v.reference_source == "voxels" else f"{v.reference_source} genus"
    if v.kind == "self_intersecting":
        return (f"self-intersecting: {_NOTE_WORDS['self_intersecting'](v.self_intersecting_faces)}, "
                "so the surface bounds no well-defined solid and no finer grid settles its genus")
    if v.kind == "no_solid":
        volume = v.solid.get("volume")
        return (f"no solid: the mesh encloses no voxel at resolution {digital[-1]['resolution']}"
                + (f" (its enclosed volume is {volume:.3g})" if volume is not None else "")
                + ", so there is no solid genus to check")
    if v.kind == "no_reference":
        return (f"no {ref_name} to compare" if digital else "no mesh genus to compare") + stop
    if v.kind == "not_converged":
        trail = ", ".join(f"{d['resolution']}: {tuple(d['betti'])}" for d in digital[-3:])
        why = ("the digital Betti numbers still change" if len(digital) > 1 else
               "one resolution cannot show that the digital Betti numbers have settled")
        return f"not converged at {digital[-1]['resolution']}: {why} ({trail})" + stop
    if v.kind == "agree":
        if v.filled_genus is not None:
            return f"agree: {_filled_words(v)}"
        return f"agree: {ref_name if v.reference_source != 'mesh' else 'genus'} {v.reference}"
    same = f"(the same at {digital[-2]['resolution']} and {digital[-1]['resolution']})"
    b0 = digital[-1]["betti"][0]
    solid = "the solid" if v.filled_genus is None else "the filled solid"
    if v.reference_source == "voxels":
        solid = "the voxels the mesh bounds"
    parts = ([f"{solid} has {counted(v.bodies, 'body', 'bodies')}, the digital solid "
              f"{counted(b0, 'component')}"] if v.bodies is not None and b0 != v.bodies else [])
    target = v.reference if v.filled_genus is None else v.filled_genus
    if digital[-1]["genus"] != target or not parts:  # (a verdict's JSON without "bodies" compares the genus)
        said = f"{ref_name} {v.reference}" if v.filled_genus is None else _filled_words(v)
        parts.insert(0, f"{said}, digital genus {digital[-1]['genus']}")
    else:
        same += f", both of genus {target}"
    return f"disagree: {'; '.join(parts)} {same}" + stop


def _filled_words(v: GenusVerdict) -> str:
    """A flood fill's target and the reference it stands in for, both."""
    return (f"filled solid genus {v.filled_genus} (the --fill flood target: the solid with its cavities filled; "
            f"the {v.reference_source}'s genus is {v.reference})")


def note_text(note: Note) -> str:
    """One note of the verdict in words."""
    return _NOTE_WORDS[note.kind](**note.facts)


#: the voxels whose digital genus a fill compares, in the note's words
_READ_AS = {"winding": "its solid is read by the generalised winding number (|w| > 1/2)",
            "shell": "its voxels are its shell (--fill shell: every voxel the surface meets)",
            "flood": "its voxels are its flood fill (--fill flood: the shell and what it encloses)"}


def _non_orientable_words(n: int) -> str:
    """The components no turning of faces makes consistent, as a clause."""
    which = "one component is" if n == 1 else f"{n} components are"
    return (f"; {which} non-orientable (no turning of its faces agrees across every edge, as a Moebius band's): "
            "no surface genus, and no inside")


def _open_words(boundary_edges: int, inconsistent_edges: int, fill: str = "winding", non_orientable: int = 0) -> str:
    return (f"the mesh is open ({counted(boundary_edges, 'boundary edge')}"
            + (f", {counted(inconsistent_edges, 'edge')} inconsistently oriented" if inconsistent_edges else "")
            + "): it bounds no solid, so it has no genus as a closed surface"
            + (_non_orientable_words(non_orientable) if non_orientable else "") + "; " + _READ_AS[fill])


def _inconsistent_words(edges: int, fill: str = "winding", genus: int | None = None, non_orientable: int = 0) -> str:
    if genus is None:
        surface = "so it has no genus as a closed surface; " + _READ_AS[fill]
    else:  # the voxeliser turns a closed component's faces to agree (isoflow.mesh.orientation): the edges balance
        read = ("its solid is read by the exact nonzero winding number, the faces turned so" if fill == "winding"
                else _READ_AS[fill])
        surface = f"its faces turned consistently make a closed surface of genus {genus}; {read}"
    odd = _non_orientable_words(non_orientable) if non_orientable else ""
    return (f"the mesh has no boundary edge, but {edges} edge{'s' if edges > 1 else ''} inconsistently oriented "
            f"(used more often one way than the other){odd}: it bounds no solid as given, {surface}")


def _point(p) -> str:
    return "(" + ", ".join(f"{x:.6g}" for x in p) + ")"


#: the rows of ``isoflow genus`` that read the mesh with its repeated faces
#: dropped; the digital rows read it as isoflow voxelize does, each copy
#: counted
_REPAIRED_ROWS = "the mesh, crossings, manifold3d, solid and pymeshlab rows"


def _repeated_words(n: int, copies: int, corners) -> str:
    listed = "twice (" if copies == n else f"more than once ({copies} copies; "
    return (f"{n} face{'s' if n > 1 else ''} listed {listed}the same three corners, the same way round; "
            f"{'the first ' if n > 1 else ''}at {', '.join(map(_point, corners))}): "
            f"{'the copies' if copies > 1 else 'the copy'} dropped for {_REPAIRED_ROWS}; the digital rows count "
            "each copy, as voxelize does (a copy adds its winding number)")


def _t_junction_words(points: int, faces: int, edges: int, digital_faces: int | None = None) -> str:
    said = (f"{counted(edges, 'boundary edge')} closed at T-junctions ({counted(points, 'vertex', 'vertices')} of one "
            f"face on another face's edge, as faces tessellated apart leave them): {counted(faces, 'face')} split "
            "there before counting")
    if digital_faces is None or digital_faces == faces:
        return said + (", for every row (the digital rows voxelise the mesh as voxelize reads it, which splits them "
                       "too: the surface drawn is the same)")
    # a repeated face dropped for the mesh rows is kept for the digital rows, which split each copy alike
    split = f"splits {counted(digital_faces, 'face')} there, each copy of a face alike" if digital_faces else \
        "leaves them whole"
    return said + (" the mesh; the digital rows voxelise it as voxelize reads it, with its repeated faces, and "
                   f"voxelize {split} (the surface drawn is the same)")


def _double_sided_words(n: int, corners, genus: int | None, walls: int = 0, union_genus: int | None = None) -> str:
    s = "s" if n > 1 else ""
    at = f"{'the first ' if n > 1 else ''}at {', '.join(map(_point, corners))}"
    if walls == n:  # solids glued face to face, not a surface drawn from both sides
        return (f"{counted(n, 'pair')} of faces on the same three corners, once each way round ({at}), all in walls "
                f"between solids: without the walls the mesh is closed, genus {union_genus}")
    said = f"{n} double-sided face{s} (the same three corners listed once each way round; {at})"
    if walls:  # walls between solids: both faces of each pair dropped leave the union's surface
        return f"{said}, {walls} in walls between solids of the {n}: without the walls the mesh is closed, genus {union_genus}"
    return said + (f"; without the later face of {'each' if n > 1 else 'the'} pair the mesh is closed, genus {genus}"
                   if genus is not None else "")


def _union_words(solid_genus: int | None, error: str | None) -> str:
    """The union's genus, or why there is none: manifold3d's error, or
    that it was not asked (``"not computed"``: the solid is built only for
    a mesh that is closed, consistently oriented and crosses nowhere)."""
    if solid_genus is not None:
        return f"genus {solid_genus} (manifold3d)"
    if error == "not computed":
        return "which is not built for a mesh that is open, inconsistently oriented or crosses itself"
    return f"which manifold3d could not build ({error})"


def _overlap_words(components: int, crossing: int, shared: int, solid_genus: int | None, error: str | None,
                   touching: int = 0, approximate: bool = False) -> str:
    union = _union_words(solid_genus, error)
    # touching faces of one component (solids stacked face to face on
    # shared corners): they meet without crossing, which is no overlap
    touch = (f"{counted(touching, 'face')} {'touch faces of their' if touching > 1 else 'touches faces of its'} own "
             "component without crossing (solids face to face)") if touching else ""
    if touching and not crossing and not shared and not approximate:
        return f"{touch}: the solid the mesh bounds is their union, {union}"
    crosses = counted(crossing, "face") + (" crosses" if crossing == 1 else " cross")
    said = (f"the mesh's {components} components overlap or touch ({crosses} other components, "
            f"{counted(shared, 'vertex', 'vertices')} shared{'; ' + touch if touch else ''})")
    if approximate:  # (solid.approximate): no nonzero-rule solid to name; say what stands in for it
        return (f"{said}, some facing opposite ways (inside-out) or too many to follow: the solid they bound by the "
                f"nonzero rule is not built; the outward components less the inside-out ones stand in for it, {union}; "
                "where surfaces facing opposite ways cross, the solid's parts touch along the crossing curves, which "
                "grids read differently")
    return f"{said}: the solid they bound is their union, {union}"


def _nonmanifold_edge_words(n: int, solid_genus: int | None = None, error: str | None = None) -> str:
    said = f"{counted(n, 'non-manifold edge')} (more than two faces)"
    if solid_genus is None and error is None:
        return said + ": not a 2-manifold, genus undefined"
    # closed sheets meeting along the edges: solids touching there, whose union is the reference
    union = _union_words(solid_genus, error)
    return said + f" where solids touch along an edge: the solid the mesh bounds is their union, {union}"


def _corner_join_words(bodies: int, components: int, by: str = "connectivity") -> str:
    counts = f"{counted(components, 'component')} for the solid's {counted(bodies, 'body', 'bodies')}"
    if by == "flood":  # the shell's voxels, which the surface meets, are shared where the solids touch
        return (f"a flood fill holds the voxels the surface meets, which join solids that touch at a point or along "
                f"an edge at any resolution: {counts}; the winding fill parts them on a fine enough grid, as "
                "manifold3d does")
    return (f"26-connected voxels join solids that touch at a point or along an edge at any resolution (voxels "
            f"meeting at a corner or an edge are one component): {counts}; 6-connected voxels part them on a fine "
            "enough grid, as manifold3d does")


def _body_count_words(bodies: int, components: int, resolution: int, pitch: float, small: int = 0) -> str:
    """The ``body_count`` note: the finest grid's digital components are
    not the solid's bodies, and the likely cause, which a finer grid may
    mend: bodies closer than a voxel, or ``small`` of the mesh's
    components shorter than a voxel on every side, which hold one voxel
    centre at most.

    Examples
    --------
    >>> _body_count_words(2, 1, 128, 0.0344813)
    "1 digital component for the solid's 2 bodies at resolution 128 (pitch 0.03448): bodies closer than a voxel \
merge at this resolution; a finer --resolution (above 128) may part them"
    >>> _body_count_words(2, 1, 256, 0.0508, small=1)
    "1 digital component for the solid's 2 bodies at resolution 256 (pitch 0.0508): 1 of the mesh's components \
is smaller than a voxel (one voxel at most, none where no voxel centre falls in it); a finer --resolution \
(above 256) may show it"
    """
    said = (f"{counted(components, 'digital component')} for the solid's {counted(bodies, 'body', 'bodies')} at "
            f"resolution {resolution} (pitch {pitch:.4g}): ")
    finer = f"a finer --resolution (above {resolution})"
    if components < bodies and small:
        merge = "; bodies closer than a voxel merge" if small < bodies - components else ""
        return said + (f"{small} of the mesh's components {'is' if small == 1 else 'are'} smaller than a voxel (one "
                       f"voxel at most, none where no voxel centre falls in {'it' if small == 1 else 'them'}){merge}; "
                       f"{finer} may show {'it' if small == 1 else 'them'}")
    if components < bodies:
        return said + f"bodies closer than a voxel merge at this resolution; {finer} may part them"
    return said + f"parts thinner than a voxel break apart at this resolution; {finer} may join them"


def _betti_words(betti) -> str:
    b0, b1, b2 = betti
    return f"{counted(b0, 'component')}, {counted(b1, 'tunnel')}, {counted(b2, 'cavity', 'cavities')}"


def _voxel_contact_words(pitch: float, shape, voxels: int, connectivity: int, betti, other, edges: int,
                         vertices: int, solid_genus: int | None = None, written: int | None = None, **_) -> str:
    where = " and ".join(([f"along {counted(edges, 'edge')}"] if edges else [])
                         + ([f"at {counted(vertices, 'vertex', 'vertices')}"] if vertices else [])) or "at shared vertices"
    said = (f"the mesh is the surface of {counted(voxels, 'voxel')} at its own grid (pitch {pitch:.6g}, "
            f"{'x'.join(map(str, shape))}) that touch {where} (edge and vertex contacts, which isoflow surface "
            f"splits and a reader's weld joins): {connectivity}-connected, as the digital rows read them, the voxels "
            f"are {_betti_words(betti)}, the reference; {32 - connectivity}-connected, {_betti_words(other)}; "
            "the mesh has no genus of its own there, and manifold3d pairs the faces at each contact by their order "
            "in the file, as neither connectivity does"
            + (f" (its solid: genus {solid_genus})" if solid_genus is not None else ""))
    if written is not None and written != connectivity:
        said += (f"; the file was written {written}-connected (--connectivity {written} reads it as written)")
    return said


def _flood_cavity_words(n: int, inside: int | None = None, handles: int | None = None) -> str:
    """What ``--fill flood`` loses of a solid with ``n`` cavities: the
    ``inside`` bodies nested in them and ``handles`` (theirs, or a cavity's
    own surface's), each said only where there are some (None: a verdict
    written before they were counted).

    Examples
    --------
    >>> _flood_cavity_words(1, 0, 0)
    "--fill flood fills the solid's 1 cavity (manifold3d), with nothing inside"
    >>> _flood_cavity_words(1, 1, 1)
    "--fill flood fills the solid's 1 cavity (manifold3d) and the body inside, whose handle its digital genus \
lacks; the default --fill winding keeps it"
    """
    said = f"--fill flood fills the solid's {counted(n, 'cavity', 'cavities')} (manifold3d)"
    if inside is None or handles is None:
        return f"{said} and the surfaces inside, whose handles its digital genus lacks; the default --fill winding keeps them"
    if inside:
        said += f" and the {'body' if inside == 1 else f'{inside} bodies'} inside"
    if handles:
        which, them = ("handle", "it") if handles == 1 else (f"{handles} handles", "them")
        return f"{said}, whose {which} its digital genus lacks; the default --fill winding keeps {them}"
    if inside:
        return f"{said}; the default --fill winding keeps {'it' if inside == 1 else 'them'}"
    return f"{said}, with nothing inside"


def _cavity_words(n: int, resolution: int, solid: int | None = None) -> str:
    """The ``cavities`` note: the digital solid's cavities (b2) at the
    finest grid, beside those of the solid manifold3d builds (``solid``;
    None where it built none). Where it has fewer, the grid's cavities are
    not nested shells of the mesh but pockets of outside that the grid
    closes off (where surfaces meet almost tangentially).

    Examples
    --------
    >>> _cavity_words(2, 64, 2)
    'the solid has 2 cavities (nested shells) at resolution 64'
    >>> _cavity_words(3, 1024, 0)
    'the digital solid has 3 cavities at resolution 1024, where the solid manifold3d builds has none: pockets of \
outside that the grid closes off'
    """
    found = counted(n, "cavity", "cavities")
    if solid is None:
        return f"the digital solid has {found} at resolution {resolution}"
    if solid == n:
        return f"the solid has {found} (nested shells) at resolution {resolution}"
    built = counted(solid, "cavity", "cavities") if solid else "none"
    return (f"the digital solid has {found} at resolution {resolution}, where the solid manifold3d builds has "
            f"{built}: pockets of outside that the grid closes off")


_NOTE_WORDS: dict[str, Callable[..., str]] = {
    "dropped_faces": lambda n: f"{n} degenerate face{'s' if n > 1 else ''} (two corners at one position) dropped",
    "welded": lambda n: (f"{counted(n, 'vertex', 'vertices')} that differ only by rounding noise were welded before counting "
                         "(tools that merge exact duplicates only see a different, open or higher-genus mesh)"),
    "repeated_faces": _repeated_words,
    "t_junctions": _t_junction_words,
    "double_sided": _double_sided_words,
    "open": _open_words,
    "inconsistent": _inconsistent_words,
    "nonmanifold_edges": _nonmanifold_edge_words,
    "nonmanifold_vertices": lambda n: (f"{counted(n, 'non-manifold vertex', 'non-manifold vertices')} where separate "
                                       "sheets touch at a point; "
                                       "genus counted with the sheets apart there (as manifold3d counts)"),
    "nested": lambda components, solid_genus: (
        f"the mesh's {components} components nest with shells facing the same way (a winding "
        "number of 2 or more inside): the solid they bound by the nonzero rule swallows the inner ones, "
        f"genus {solid_genus} (manifold3d)"),
    "overlap": _overlap_words,
    "self_intersecting": lambda n: f"{counted(n, 'face')} cross{'es' if n == 1 else ''} faces of their own component",
    "zero_area_faces": lambda n, along: (
        f"{n} zero-area face{'s' if n > 1 else ''} (corners in a line) left out of the crossing test"
        + (f"; {along} face pair{'s' if along > 1 else ''} meet{'' if along > 1 else 's'} along "
           f"{'them' if n > 1 else 'it'} where {'they close' if n > 1 else 'it closes'} a split edge (a T-junction): "
           "no crossing" if along else "")),
    "float64_rounding": lambda near, spacing, median_edge, share, defects=(), precision="float64": rounding_words(
        near, spacing, median_edge, share, tuple(defects), " above", precision),
    "cavities": _cavity_words,
    "flood_cavities": _flood_cavity_words,
    "coarse": lambda resolution, genus, pitch: (
        f"at resolution {resolution} the grid is too coarse: digital genus {genus} "
        f"(pitch {pitch:.4g}; handles thinner than a voxel close or open)"),
    "manifold3d_refused": lambda error: f"manifold3d refused the mesh ({error})",
    "corner_joins": _corner_join_words,
    "body_count": _body_count_words,
    "thin_overlap": lambda thickness, at, voxels, resolution: (
        f"two components overlap in a lens {thickness:.2g} thick on average at {_point(at)}, {voxels:.2g} "
        f"voxel{'s' if voxels >= 1.5 else ''} at resolution {resolution}: their surfaces meet almost tangentially, "
        "and the crevice around the lens, narrower than a voxel over a band many voxels wide, leaves pockets and "
        "tunnels of outside that change with the grid"),
    "no_mesh_genus": lambda: "the mesh is not a closed oriented manifold, so it has no genus",
    "voxel_contacts": _voxel_contact_words,
    "written_connectivity": lambda connectivity: f"digital rows {connectivity}-connected, as the file was written",
}


def strict_refusal(said: str, unstrict: str) -> IsoflowError:
    """The refusal of ``verify_genus(strict=True)``: ``said``, why the mesh
    is refused, then ``unstrict``, what genus does without the option, in
    Python's words and the command line's.

    Examples
    --------
    >>> strict_refusal("m.obj: mesh is not watertight", "genus counts it").command_line
    'm.obj: mesh is not watertight (without --strict genus counts it)'
    """
    return IsoflowError.worded(f"{said} (without strict=True {unstrict})", f"{said} (without --strict {unstrict})")
