"""Rewriting SDF trees so PyBullet loads them as Gazebo would.

Mesh URIs are made absolute, ASCII STL meshes are converted to binary (PyBullet crashes on
them), OBJ meshes without faces are rejected, the root link's pose is folded into the model
pose, and extra root links are tied to the first with fixed joints; what cannot be fixed is
reported as an :class:`~fleet_async.core.scenario.gazebo_world.AssetProblem`.
"""

from __future__ import annotations

import copy
import re
import struct
import xml.etree.ElementTree as ET
from pathlib import Path as FsPath

import pybullet_data

from fleet_async.core.geometry.pose import Pose
from fleet_async.core.scenario.gazebo_world import (
    AssetProblem,
    ModelSearch,
    format_pose,
    parse_pose,
    sdf_models,
)

__all__ = ["SdfRewriter", "ascii_stl_to_binary", "check_obj", "is_binary_stl"]


def _is_identity(pose: Pose) -> bool:
    return bool(
        abs(pose.position).max() < 1e-12 and abs(abs(float(pose.orientation[3])) - 1.0) < 1e-12
    )


def _set_pose(holder: ET.Element, pose: Pose) -> None:
    element = holder.find("pose")
    if element is None:
        element = ET.SubElement(holder, "pose")
    element.attrib.clear()
    element.text = format_pose(pose)


_MODEL_FRAMES = ("", "world", "__model__")


def _link_pose(link: ET.Element, where: str) -> Pose:
    element = link.find("pose")
    if element is not None and (element.get("relative_to") or "").strip() in _MODEL_FRAMES:
        element = copy.copy(element)
        element.attrib.pop("relative_to", None)
    return parse_pose(element, where)


class SdfRewriter:
    """Makes SDF trees loadable by PyBullet; writes rewritten copies into ``workdir``.

    Args:
        search: Resolves ``model://`` URIs.
        workdir: Directory for rewritten SDF files and converted meshes (the caller deletes it).
    """

    def __init__(self, search: ModelSearch, workdir: FsPath) -> None:
        self.search = search
        self.workdir = workdir
        self._meshes: dict[FsPath, FsPath] = {}
        self._written = 0

    def prepare(self, root: ET.Element, base_dir: FsPath) -> tuple[bool, list[AssetProblem]]:
        """Rewrite ``root`` in place for PyBullet.

        Args:
            root: Parsed SDF tree.
            base_dir: Directory relative mesh URIs are resolved against.

        Returns:
            (changed, problems): whether the tree now differs from its file, and everything
            that stops it from loading (empty when it can be loaded).
        """
        problems = [
            AssetProblem(
                f"<include> of {(inc.findtext('uri') or '?').strip()!r} inside an SDF file: "
                "PyBullet's SDF loader cannot include models; load the file as a 'world_file'"
            )
            for inc in root.iter("include")
        ]
        changed = False
        for model in sdf_models(root):
            try:
                changed |= self._fix_links(model)
            except AssetProblem as problem:
                problems.append(problem)
        for mesh in root.iter("mesh"):
            try:
                changed |= self._fix_mesh_uri(mesh, base_dir)
            except AssetProblem as problem:
                problems.append(AssetProblem(f"mesh {problem.reason}", problem.paths))
        return changed, problems

    def _fix_mesh_uri(self, mesh: ET.Element, base_dir: FsPath) -> bool:
        """Point a ``<mesh><uri>`` at a checked absolute file; return whether it changed."""
        uri = mesh.find("uri")
        if uri is None or not (uri.text or "").strip():
            raise AssetProblem("<mesh> without a <uri>")
        text = str(uri.text).strip()
        found = self.search.resolve(text, base_dir, [FsPath(pybullet_data.getDataPath())])
        checked = str(self.mesh_file(found))
        if checked == text:
            return False
        uri.text = checked
        return True

    def _fix_links(self, model: ET.Element) -> bool:
        """Fold the root link pose into the model pose and tie extra root links with joints."""
        name = model.get("name", "")
        nested = [m.get("name", "") for m in model.findall("model")]
        if nested:
            raise AssetProblem(
                f"model {name!r}: nested <model> {nested} is not supported by PyBullet's SDF loader"
            )
        links = model.findall("link")
        if not links:
            raise AssetProblem(f"model {name!r} has no <link>")
        children = {(j.findtext("child") or "").strip() for j in model.findall("joint")}
        roots = [link for link in links if link.get("name", "") not in children]
        if not roots:
            raise AssetProblem(f"model {name!r}: every link is a joint child (no root link)")
        first = roots[0]
        root_pose = _link_pose(first, f"model {name!r} link {first.get('name')!r}")
        changed = False
        if not _is_identity(root_pose):
            # PyBullet ignores the root link's pose; move it into the model pose instead and
            # re-express the other links (model-frame poses) in the new model frame.
            model_pose = parse_pose(model.find("pose"), f"model {name!r}")
            to_root = root_pose.inverse()
            for link in links:
                if link is not first:
                    where = f"model {name!r} link {link.get('name')!r}"
                    _set_pose(link, to_root.compose(_link_pose(link, where)))
            _set_pose(model, model_pose.compose(root_pose))
            _set_pose(first, Pose([0.0, 0.0, 0.0]))
            changed = True
        for i, extra in enumerate(roots[1:], start=1):
            # Several root links crash PyBullet; a fixed joint keeps each where it is.
            joint = ET.SubElement(
                model, "joint", {"name": f"fleet_async_fixed_{i}", "type": "fixed"}
            )
            ET.SubElement(joint, "parent").text = first.get("name", "")
            ET.SubElement(joint, "child").text = extra.get("name", "")
            changed = True
        return changed

    def mesh_file(self, path: FsPath) -> FsPath:
        """Check a mesh file PyBullet will read; ASCII STL comes back converted to binary.

        Raises:
            AssetProblem: for a missing file, an OBJ without faces or an invalid STL.
        """
        path = path.resolve()
        if path not in self._meshes:
            self._meshes[path] = self._checked_mesh(path)
        return self._meshes[path]

    def _checked_mesh(self, path: FsPath) -> FsPath:
        if not path.is_file():
            raise AssetProblem(f"file {path} does not exist", [path])
        suffix = path.suffix.lower()
        if suffix == ".obj":
            check_obj(path)
        elif suffix == ".stl":
            data = path.read_bytes()
            if not is_binary_stl(data):
                converted = self.workdir / f"mesh{len(self._meshes)}_{path.stem}.stl"
                converted.write_bytes(ascii_stl_to_binary(data, path))
                return converted
        return path

    def write(self, root: ET.Element, stem: str) -> FsPath:
        """Write ``root`` to a new SDF file in the work directory and return its path."""
        self._written += 1
        safe = re.sub(r"[^A-Za-z0-9_.-]+", "_", stem) or "model"
        path = self.workdir / f"{self._written:04d}_{safe}.sdf"
        ET.ElementTree(root).write(path, encoding="utf-8", xml_declaration=True)
        return path


def check_obj(path: FsPath) -> None:
    """Raise AssetProblem unless an OBJ file has vertices and faces (PyBullet rejects it)."""
    seen = {"v": False, "f": False}
    with path.open("r", encoding="utf-8", errors="replace") as lines:
        for line in lines:
            word = line.split(maxsplit=1)[0] if line.strip() else ""
            if word in seen:
                seen[word] = True
                if all(seen.values()):
                    return
    missing = "vertices" if not seen["v"] else "faces"
    raise AssetProblem(f"file {path} is not a usable OBJ mesh: it has no {missing}", [path])


def is_binary_stl(data: bytes) -> bool:
    """Whether ``data`` is a binary STL whose triangle count fits its size."""
    if len(data) < 84:
        return False
    (count,) = struct.unpack_from("<I", data, 80)
    expected = 84 + 50 * count
    if count == 0 or len(data) < expected:
        return False
    # Binary files may carry trailing bytes, but ASCII ones also start with "solid".
    return len(data) == expected or not data.lstrip().startswith(b"solid")


_VERTEX = re.compile(rb"^\s*vertex\s+(\S+)\s+(\S+)\s+(\S+)", re.MULTILINE)


def ascii_stl_to_binary(data: bytes, path: FsPath) -> bytes:
    """Convert an ASCII STL to binary (PyBullet's STL reader crashes on ASCII).

    Raises:
        AssetProblem: if ``data`` is not a valid ASCII STL either.
    """
    if not data.lstrip().startswith(b"solid"):
        raise AssetProblem(
            f"file {path} is not a valid STL mesh (neither binary nor ASCII)", [path]
        )
    try:
        vertices = [tuple(float(v) for v in m) for m in _VERTEX.findall(data)]
    except ValueError:
        raise AssetProblem(f"file {path}: ASCII STL has a non-numeric vertex", [path]) from None
    if not vertices or len(vertices) % 3:
        raise AssetProblem(
            f"file {path}: ASCII STL needs 3 vertices per facet, found {len(vertices)}", [path]
        )
    out = bytearray(b"fleet_async: converted from ASCII STL".ljust(80, b" "))
    out += struct.pack("<I", len(vertices) // 3)
    for i in range(0, len(vertices), 3):
        out += struct.pack("<3f", 0.0, 0.0, 0.0)  # normal: recomputed by readers
        for vertex in vertices[i : i + 3]:
            out += struct.pack("<3f", *vertex)
        out += b"\0\0"
    return bytes(out)
