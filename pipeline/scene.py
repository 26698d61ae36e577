"""Scene files (TOML): what the user wants computed, validated against the stages' schema.

Layout::

    name = "default"                 # optional; names the output folder
    description = "..."              # optional
    [substrate] / [solid] / [interface] / [material] / [load] / ...   (declared by stages)
    [outputs]  variables = ["contact_area_ratio", ...]
    [numerics] points_per_decade = 50, ..., chunks = { p = 1000 }
    [variants.NAME]  overrides of any of the above, computed as well (e.g. substrate_only)

Unknown keys are errors with a did-you-mean; every quantity is converted to SI.
"""

from __future__ import annotations

import copy
import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

from . import scenecache
from .errors import UserError
from .schema import Param, Section, did_you_mean
from .stage import register_section, sections

register_section(
    Section(
        "outputs",
        (Param("variables", "list", default=("contact_area_ratio",),
               doc="variables (or stage names) to compute; only the stages they need run"),),
        doc="what the scene asks for",
    )
)

register_section(
    Section(
        "run",
        (Param("scheduler", "str", default="threads",
               doc="where dask computes: 'threads', 'processes', 'synchronous', or the address of a "
                   "dask.distributed scheduler (tcp://host:port); never part of a result's key"),
         Param("compress", "bool", default=True,
               doc="zlib-compress variables of 16 KiB and more where a trial block shrinks to 80 % or less "
                   "(1e8 contact areas: 600 instead of 771 MiB, in worker threads beside the computation; "
                   "the values are the same either way)"),),
        doc="how the engine runs (does not change results)",
    )
)

TOP_LEVEL = {"name": "str", "description": "str"}
#: keys of [numerics] that belong to the engine (chunking, presets), not to any stage
ENGINE_NUMERICS = ("chunks", "chunk_mb", "preset")
PRESETS = ("fast", "default", "accurate")


@dataclass
class Scene:
    """A validated scene: every value in SI, keyed by section then parameter."""

    name: str
    values: dict[str, Any]
    path: Path | None = None
    description: str = ""
    chunks: dict[str, int] = field(default_factory=dict)
    chunk_mb: float = 32.0
    preset: str = "default"
    raw: dict = field(default_factory=dict)
    variants: dict[str, "Scene"] = field(default_factory=dict)
    variant: str = "base"

    def sweep_sizes(self) -> dict[str, int]:
        """Sizes of the sweep dimensions this scene defines (e.g. {"p": 101, "eta": 3})."""
        out: dict[str, int] = {}
        for name, section in sections().items():
            out.update(section.sweep_dims(self.values.get(name)))
        return out

    @property
    def outputs(self) -> tuple[str, ...]:
        return tuple(self.values["outputs"]["variables"])

    def get(self, dotted: str):
        """Value of ``section`` (a dict or None) or ``section.key``."""
        section, _, key = dotted.partition(".")
        if section not in self.values:
            raise KeyError(dotted)
        value = self.values[section]
        if not key:
            return value
        if value is None:
            return None
        return value.get(key)

    @property
    def label(self) -> str:
        return f"{self.path or '<built-in ' + self.name + '>'}"


def units_of(dotted: str) -> str | None:
    """The SI units of the quantity at scene key ``dotted`` (``material.E`` -> ``Pa``), None when
    the key is not a quantity (or unknown)."""
    section, _, key = dotted.partition(".")
    sec = sections().get(section)
    if sec is None:
        return None
    params = list(sec.params) + [p for ps in sec.variants.values() for p in ps]
    found = [p for p in params if p.name == key.rpartition(".")[2]]
    return found[0].units if found and found[0].kind in ("quantity", "sweep", "quantities") else None


def default_scene_path() -> Path:
    return Path(str(resources.files(__package__) / "scenes" / "default.toml"))


def builtin_scenes() -> dict[str, Path]:
    folder = resources.files(__package__) / "scenes"
    return {Path(str(p)).stem: Path(str(p)) for p in folder.iterdir() if str(p).endswith(".toml")}


def builtin_descriptions() -> dict[str, str]:
    """Each built-in scene's one-line ``description`` (its name when it has none)."""
    out = {}
    for name, path in builtin_scenes().items():
        try:
            out[name] = tomllib.loads(path.read_text(encoding="utf-8")).get("description", "") or name
        except (OSError, tomllib.TOMLDecodeError) as exc:
            out[name] = f"(unreadable: {exc})"
    return out


def copy_builtin(name: str, folder: str | Path) -> list[Path]:
    """Copy the built-in scene ``name`` and every data file it (or a variant) reads into
    ``folder``, in the same layout (``NAME.toml``, ``data/...``), so that the copy runs as it is.
    Returns the files written; refuses (writing nothing) to overwrite a file."""
    import shutil

    builtin = builtin_scenes()
    if name not in builtin:
        raise UserError(f"no built-in scene {name!r} (built-in scenes: {', '.join(sorted(builtin))})"
                        f"{did_you_mean(name, builtin)}", key="--copy")
    source = builtin[name]
    home = source.parent.resolve()
    scene = load(source)
    data = {f for sc in (scene, *scene.variants.values()) for f in _files_in(sc.values) if home in f.resolve().parents}
    sources = [source, *sorted(data)]
    folder = Path(folder)
    targets = [folder / f.resolve().relative_to(home) for f in sources]
    for target in targets:
        if target.exists() or (target.parent.exists() and not target.parent.is_dir()):
            raise UserError("exists already: copy into another folder, or move it away", file=str(target))
    try:
        for src, target in zip(sources, targets, strict=True):
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(src, target)
    except OSError as exc:
        raise UserError(f"cannot copy the scene here ({exc.strerror or exc})", file=str(folder)) from None
    return targets


def _files_in(value) -> list[Path]:
    """Every existing file a scene's (SI) values name, however deep."""
    if isinstance(value, dict):
        return [f for v in value.values() for f in _files_in(v)]
    if isinstance(value, (list, tuple)):
        return [f for v in value for f in _files_in(v)]
    return [value] if isinstance(value, Path) and value.is_file() else []


def resolve(scene: str | None) -> Path:
    """A scene argument: a file path, or the name of a built-in scene, or None (default)."""
    if scene is None:
        return default_scene_path()
    path = Path(scene)
    if path.is_file():
        return path
    builtin = builtin_scenes()
    if scene in builtin:
        return builtin[scene]
    raise UserError(
        f"no scene file {scene!r} (built-in scenes: {', '.join(sorted(builtin))}){did_you_mean(scene, builtin)}"
    )


def load(scene: str | Path | None, preset: str | None = None) -> Scene:
    """Read and validate a scene file (or a built-in scene name; None: the default scene).

    ``preset`` (fast, default, accurate) overrides the scene's ``[numerics] preset``; settings
    the scene gives explicitly always win over a preset."""
    path = resolve(str(scene) if scene is not None else None)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise UserError(f"cannot read: {exc}", file=str(path)) from None
    return scenecache.load(path, data, preset, lambda: _parse(path, data, preset))


def _parse(path: Path, data: bytes, preset: str | None) -> Scene:
    try:
        raw = tomllib.loads(data.decode("utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise UserError(f"malformed TOML: {exc}", file=str(path)) from None
    except UnicodeDecodeError as exc:
        raise UserError(f"cannot read: {exc}", file=str(path)) from None
    if preset is not None:
        raw.setdefault("numerics", {})["preset"] = preset
    return from_dict(raw, path)


def from_dict(raw: dict, path: Path | None = None, *, variant: str = "base") -> Scene:
    """Validate a scene given as a (TOML-like) dict; TOML text is parsed first, and numpy arrays
    and scalars in it are taken as lists and numbers."""
    if isinstance(raw, (str, bytes)):
        raw = _parse_text(raw)
    if not isinstance(raw, dict):
        raise TypeError(f"a scene is a dict (or TOML text), got {type(raw).__name__}; for a scene file or a "
                        "built-in scene name use roughcontact.scene.load(...)")
    try:
        return _from_dict(_plain(raw), path, variant)
    except UserError as exc:
        raise exc.located(file=str(path) if path else None) from None


def _parse_text(text) -> dict:
    """A scene given as TOML text."""
    try:
        return tomllib.loads(text.decode() if isinstance(text, bytes) else text)
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise UserError(f"from_dict takes a dict or TOML text, and this text is not TOML ({exc}); for a scene file "
                        "or a built-in scene name use roughcontact.scene.load(...)") from None


def _plain(value):
    """numpy arrays and scalars as the lists and numbers TOML would give."""
    import numpy as np

    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [_plain(v) for v in (value.tolist() if isinstance(value, np.ndarray) else value)]
    return value.item() if isinstance(value, np.generic) else value


def check_name(name) -> str:
    """A scene name names its output folder (outputs/<name>): a plain name, never a path."""
    if not isinstance(name, str):
        raise UserError(f"expected a string, got {name!r}", key="name")
    if name in ("", ".", "..") or name.startswith((".", "~")) or any(c in name for c in "/\\\0:"):
        raise UserError(f"{name!r} is not a plain name: the scene name names the output folder outputs/<name>, so "
                        "it may not contain '/', '\\', ':' or start with '.' or '~' (use --outdir to write elsewhere)",
                        key="name")
    return name


def _from_dict(raw: dict, path: Path | None, variant: str) -> Scene:
    schema = sections()
    raw = copy.deepcopy(raw)
    original = copy.deepcopy(raw)
    variants_raw = raw.pop("variants", {}) if variant == "base" else {}
    for key, value in raw.items():
        if key in TOP_LEVEL:
            if not isinstance(value, str):
                raise UserError(f"expected a string, got {value!r}", key=key)
        elif key not in schema:
            known = list(schema) + list(TOP_LEVEL) + ["variants"]
            raise UserError(f"unknown key {key!r}{did_you_mean(key, known)}", key=key)
    numerics = raw.get("numerics") if isinstance(raw.get("numerics"), dict) else None
    chunks = _chunks(numerics.pop("chunks", {}) if numerics is not None else {})
    chunk_mb = numerics.pop("chunk_mb", 32.0) if numerics is not None else 32.0
    preset = numerics.pop("preset", "default") if numerics is not None else "default"
    if preset not in PRESETS:
        raise UserError(f"preset {preset!r} is not one of {', '.join(PRESETS)}{did_you_mean(str(preset), PRESETS)}",
                        key="numerics.preset")
    if isinstance(chunk_mb, bool) or not isinstance(chunk_mb, (int, float)) or not 0.01 <= chunk_mb <= 65536:
        raise UserError(f"must be a number of MB between 0.01 and 65536, got {chunk_mb!r}", key="numerics.chunk_mb")
    base_dir = path.parent if path else None
    values = {name: section.convert(raw.get(name), base_dir, preset=preset) for name, section in schema.items()}
    scene = Scene(
        name=check_name(raw["name"]) if "name" in raw else (path.stem if path else "scene"),
        description=raw.get("description", ""),
        values=values,
        path=path,
        chunks=chunks,
        chunk_mb=float(chunk_mb),
        preset=preset,
        raw=original,
        variant=variant,
    )
    if not isinstance(variants_raw, dict):
        raise UserError("expected tables [variants.NAME]", key="variants")
    base_raw = copy.deepcopy(raw)
    if numerics is not None:
        base_raw["numerics"]["chunks"] = dict(chunks)
        base_raw["numerics"]["chunk_mb"] = chunk_mb
        base_raw["numerics"]["preset"] = preset
    for name, override in variants_raw.items():
        if not isinstance(override, dict):
            raise UserError("expected a table of overrides", key=f"variants.{name}")
        if not name.isidentifier() or name == "base":
            raise UserError("a variant name must be an identifier other than 'base'", key=f"variants.{name}")
        try:
            scene.variants[name] = _from_dict(_merge(base_raw, override), path, name)
        except UserError as exc:
            raise UserError(exc.message, key=f"variants.{name}.{exc.key}" if exc.key else f"variants.{name}") from None
        scene.variants[name].name = scene.name
    return scene


def _merge(base: dict, override: dict) -> dict:
    """Overlay ``override`` on ``base``; a table that sets ``kind`` replaces the whole table."""
    out = copy.deepcopy(base)
    for key, value in override.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict) and "kind" not in value:
            out[key] = _merge(out[key], value)
        else:
            out[key] = copy.deepcopy(value)
    return out


def _chunks(raw) -> dict[str, int]:
    if not isinstance(raw, dict):
        raise UserError("expected a table like { p = 1000 }", key="numerics.chunks")
    for dim, size in raw.items():
        if isinstance(size, bool) or not isinstance(size, int) or size < 0:
            raise UserError(f"chunk size must be a whole number >= 0, got {size!r}", key=f"numerics.chunks.{dim}")
        if dim == "q":
            raise UserError("q is the core dimension of the integrals and is never chunked", key="numerics.chunks.q")
    return dict(raw)


def reference() -> str:
    """The scene-file reference in Markdown, generated from the registered sections."""
    lines = [
        "# Scene-file reference",
        "",
        "Generated by `roughcontact reference` from the parameters the stages declare; do not edit by hand.",
        "Quantities are strings with units (`\"1 nm\"`, `\"77.2 GPa\"`, `\"2e8 1/m\"`, `\"100 meV/angstrom^2\"`);",
        "a *sweep* is one quantity, a list of them (a sweep dimension), `{ values = [1, 2], unit = \"MPa\" }`,",
        "or a range `{ from = \"1 MPa\", to = \"1 GPa\", num = 50, spacing = \"log\" }`.",
        "Top-level keys: `name` (names the output folder), `description`. `[numerics] chunks = { p = 1000 }`",
        "sets dask chunk sizes per sweep dimension; otherwise sweeps are chunked automatically so that a",
        "chunk's working memory stays near `[numerics] chunk_mb` (default 32). Chunking never changes results",
        "and is not part of a result's key. `[numerics] preset = \"fast\" | \"default\" | \"accurate\"` (or",
        "`--preset` on the command line) picks every resolution setting the scene does not set itself;",
        "the reference lists each setting's preset values. `[variants.NAME]` tables override any key and are",
        "computed alongside (e.g. `[variants.substrate_only] solid = { kind = \"smooth\" }`).",
        "",
    ]
    # sections and the keys of [numerics] (which several stage modules fill) in a fixed order, whatever
    # order the modules happened to be imported in
    ordered = sorted(sections().items(), key=lambda item: (item[0] in ("outputs", "run", "numerics"), item[0]))
    for name, section in ordered:
        lines.append(f"## [{name}]" + (" (optional)" if section.optional else ""))
        if section.doc:
            lines.append(f"{section.doc}.\n")
        lines.append("| key | kind | units | default | meaning |\n|---|---|---|---|---|")
        groups = [("", sorted(section.params, key=lambda p: p.name) if name == "numerics" else section.params)]
        if section.discriminator:
            groups += [(f"{section.discriminator} = \"{k}\": ", ps) for k, ps in section.variants.items()]
        for prefix, params in groups:
            for p in params:
                from .schema import REQUIRED

                if p.default is REQUIRED:
                    default = "required"
                elif p.default is None:
                    default = "-"
                else:
                    shown = list(p.default) if isinstance(p.default, tuple) else p.default
                    default = f"`{shown}`"
                choices = f" ({', '.join(map(str, p.choices))})" if p.choices else ""
                if p.presets:
                    presets = {**p.presets, "default": p.default}
                    choices += " [presets: " + ", ".join(f"{k} {v}" for k, v in presets.items()) + "]"
                lines.append(f"| `{p.name}` | {p.kind} | {p.units or '-'} | {default} | {prefix}{p.doc}{choices} |")
        lines.append("")
    return "\n".join(lines)
