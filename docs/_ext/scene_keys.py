"""The scene-key reference, generated from the pydantic schema at build time.

`SCHEMA` is the one place that names the schema class: change it when the module moves.
`python docs/_ext/scene_keys.py [OUT.md]` writes the page; as a Sphinx extension
(`extensions = ["scene_keys"]`) it writes `docs/reference/scene_keys.md` before the build
reads its sources, so the page cannot drift from the code.

Per key: its path (`particles.blocks[].min`: `[]` marks a list of tables), type, unit,
default, constraint and description. The description is the field's pydantic
`description`; a trailing `[unit]` in it goes to the unit column (or
`json_schema_extra={"unit": ...}`). A field without a description shows the comment
beside it in the source, marked "(source comment)", until it has one
(`tests/test_docs_keys.py` checks that every field has a description).
"""

from __future__ import annotations

import importlib
import inspect
import re
import sys
import types
import typing
from dataclasses import dataclass
from pathlib import Path

from annotated_types import Ge, Gt, Le, Lt, MaxLen, MinLen
from pydantic import BaseModel
from pydantic_core import PydanticUndefined

SCHEMA = "psph.config.schema:Scene"  # module:class of the root scene model

ROOT = Path(__file__).resolve().parents[2]
PAGE = Path(__file__).resolve().parents[1] / "reference" / "scene_keys.md"


def schema_class() -> type[BaseModel]:
    module, name = SCHEMA.split(":")
    if str(ROOT) not in sys.path:
        sys.path.insert(0, str(ROOT))
    return getattr(importlib.import_module(module), name)


@dataclass
class Key:
    path: str
    type: str
    unit: str
    default: str
    rule: str
    description: str
    described: bool  # has a pydantic description (not a source comment)
    model: str  # the model class that declares the field


# ------------------------------------------------------------------ types


def _strip(annotation):
    """(bare annotation, constraints) without Annotated wrappers."""
    rules = []
    while typing.get_origin(annotation) is typing.Annotated:
        annotation, *meta = typing.get_args(annotation)
        for m in meta:
            rules.extend(getattr(m, "metadata", []) or [m])
    return annotation, rules


def _is_model(t) -> bool:
    return inspect.isclass(t) and issubclass(t, BaseModel)


def _union_args(t):
    if typing.get_origin(t) in (typing.Union, types.UnionType):
        return list(typing.get_args(t))
    return [t]


def type_name(t) -> str:
    t, rules = _strip(t)
    origin = typing.get_origin(t)
    if origin in (typing.Union, types.UnionType):
        return " \\| ".join(type_name(a) for a in typing.get_args(t))
    if origin is typing.Literal:
        return " \\| ".join(repr(a).replace("'", '"') for a in typing.get_args(t))
    if origin is list:
        (inner,) = typing.get_args(t)
        inner_t, inner_rules = _strip(inner)
        if not _is_model(inner_t) and typing.get_origin(inner_t) is None and \
                any(isinstance(r, (MinLen, MaxLen)) for r in inner_rules):
            lens = {type(r).__name__: getattr(r, "min_length", getattr(r, "max_length", None))
                    for r in inner_rules}
            if lens.get("MinLen") == lens.get("MaxLen") == 2:
                return f"list of [{type_name(inner_t)}, {type_name(inner_t)}]"
        n = ""
        mins = [r.min_length for r in rules if isinstance(r, MinLen)]
        maxs = [r.max_length for r in rules if isinstance(r, MaxLen)]
        if mins and maxs and mins == maxs:
            return f"[{type_name(inner)}] × {mins[0]}"
        return f"list of {type_name(inner)}{n}"
    if origin is dict:
        k, v = typing.get_args(t)
        return f"table of {type_name(k)} → {type_name(v)}"
    if t is type(None):
        return "none"
    if _is_model(t):
        return f"table ({t.__name__})"
    return getattr(t, "__name__", str(t))


def _vec_rule(t) -> list[str]:
    """Length rules of a list annotation (e.g. [x, y] pairs)."""
    t, rules = _strip(t)
    out = []
    mins = [r.min_length for r in rules if isinstance(r, MinLen)]
    maxs = [r.max_length for r in rules if isinstance(r, MaxLen)]
    if typing.get_origin(t) is list:
        if mins and maxs and mins == maxs:
            out.append(f"exactly {mins[0]} items")
        elif mins:
            out.append(f"at least {mins[0]} items")
        elif maxs:
            out.append(f"at most {maxs[0]} items")
    return out


def rule_text(field) -> str:
    rules = []
    metas = list(field.metadata)
    ann = field.annotation
    for arg in _union_args(ann):
        metas.extend(_strip(arg)[1])
        rules.extend(_vec_rule(arg))
    sym = {Gt: ("> ", "gt"), Ge: ("≥ ", "ge"), Lt: ("< ", "lt"), Le: ("≤ ", "le")}
    for m in metas:
        for cls, (s, attr) in sym.items():
            if isinstance(m, cls):
                rules.append(f"{s}{getattr(m, attr)}")
        if isinstance(m, MinLen) and not any("items" in r for r in rules):
            rules.append(f"at least {m.min_length} items")
    lo = [m.min_length for m in metas if isinstance(m, MinLen)]
    hi = [m.max_length for m in metas if isinstance(m, MaxLen)]
    if lo and hi and lo[0] == hi[0]:
        rules = [r for r in rules if "items" not in r] + [f"exactly {lo[0]} items"]
    elif hi:
        rules.append(f"at most {hi[0]} items")
    if field.is_required():
        rules.insert(0, "required")
    seen, out = set(), []
    for r in rules:
        if r not in seen:
            seen.add(r)
            out.append(r)
    return ", ".join(out)


def default_text(field) -> str:
    if field.is_required():
        return "—"
    d = field.default
    if d is PydanticUndefined:
        d = field.default_factory() if field.default_factory else None
    if d is None:
        return "none"
    if isinstance(d, BaseModel):
        return "(table)"
    if isinstance(d, bool):
        return "true" if d else "false"
    if isinstance(d, str):
        return f'"{d}"'
    if d == [] or d == {}:
        return "[]" if d == [] else "{}"
    return repr(d)


# ------------------------------------------------------------------ source comments


def _source_comments(model: type[BaseModel]) -> dict[str, str]:
    """Field name -> the comment beside it (trailing) or the comment lines just above it,
    from the class that declares it."""
    out: dict[str, str] = {}
    for cls in reversed(model.__mro__):
        if not _is_model(cls) or cls is BaseModel:
            continue
        try:
            lines, _ = inspect.getsourcelines(cls)
        except (OSError, TypeError):
            continue
        above: list[str] = []
        for line in lines[1:]:
            s = line.strip()
            if s.startswith("#"):
                above.append(s.lstrip("#").strip())
                continue
            m = re.match(r"\s+(\w+)\s*:", line)
            if m and not s.startswith(("def ", "@", "return", "\"\"\"")):
                name = m.group(1)
                trailing = ""
                if "  # " in line:
                    trailing = line.split("  # ", 1)[1].strip()
                text = " ".join(above + ([trailing] if trailing else []))
                if text:
                    out[name] = text
            above = []
    return out


def _unit_and_text(desc: str, extra) -> tuple[str, str]:
    unit = ""
    if isinstance(extra, dict) and extra.get("unit"):
        unit = str(extra["unit"])
    m = re.search(r"\s*\[([^\[\]]+)\]\s*$", desc)
    if m:
        unit = unit or m.group(1)
        desc = desc[: m.start()].rstrip()
    return unit, desc


# ------------------------------------------------------------------ walk


def walk(model: type[BaseModel] | None = None, prefix: str = "") -> list[Key]:
    """Every key of the schema, depth first, tables after their own row."""
    model = model or schema_class()
    comments = _source_comments(model)
    keys: list[Key] = []
    for name, field in model.model_fields.items():
        path = f"{prefix}{name}"
        desc = (field.description or "").strip()
        described = bool(desc)
        unit, desc = _unit_and_text(desc, field.json_schema_extra)
        if not described and name in comments:
            desc = f"{comments[name]} (source comment)"
        declared = next((c.__name__ for c in model.__mro__
                         if name in getattr(c, "__annotations__", {})), model.__name__)
        keys.append(Key(path, type_name(field.annotation), unit, default_text(field),
                        rule_text(field), _md(desc), described, declared))
        for arg in _union_args(_strip(field.annotation)[0]):
            arg, _ = _strip(arg)
            if _is_model(arg):
                keys.extend(walk(arg, f"{path}."))
            elif typing.get_origin(arg) is list:
                (inner,) = typing.get_args(arg)
                inner, _ = _strip(inner)
                if _is_model(inner):
                    keys.extend(walk(inner, f"{path}[]."))
    return keys


def _md(text: str) -> str:
    """Text safe in a Markdown table cell."""
    return text.replace("|", "\\|").replace("<", "&lt;").replace(">", "&gt;")


def _row(k: Key) -> str:
    return (f"| `{k.path}` | {k.type} | {k.unit or ''} | {k.default} | {k.rule} | "
            f"{k.description} |")


def render(keys: list[Key] | None = None) -> str:
    keys = keys if keys is not None else walk()
    root = schema_class()
    lines = [
        "# Scene keys",
        "",
        "<!-- generated by docs/_ext/scene_keys.py from the pydantic schema: do not edit -->",
        "",
        f"Every key of a scene, generated at build time from the schema (`{SCHEMA}` and the",
        "models it nests), so this page cannot drift from the code. `a[].b` is key `b` of",
        "each table of the list `a` (`[[a]]` in TOML). Units are SI. A key shown with",
        "\"(source comment)\" has no description in the schema yet: its text is the comment",
        "beside it in the source. The rules between keys (e.g. `time.dt` against the",
        "stability limits) are checked after these per-key rules and are listed in",
        "[Scenes](../guide/scenes.md) and [Pressure schemes](../guide/pressure_schemes.md).",
        "",
    ]
    scalars = [k for k in keys if "." not in k.path and "[]" not in k.path
               and not k.type.startswith(("table", "list of table"))
               and not any(j.path.startswith(k.path + ".") for j in keys)]
    if scalars:
        lines += ["## Top level", "", "| key | type | unit | default | rule | description |",
                  "|---|---|---|---|---|---|"]
        lines += [_row(k) for k in scalars] + [""]
    top = [k for k in keys if "." not in k.path and k not in scalars]
    for section in top:
        sub = [k for k in keys if k.path == section.path or
               k.path.startswith(section.path + ".") or k.path.startswith(section.path + "[]")]
        lines += [f"## `{section.path}`", ""]
        lines += ["| key | type | unit | default | rule | description |",
                  "|---|---|---|---|---|---|"]
        lines += [_row(k) for k in sub] + [""]
    lines.append(f"{len(keys)} keys in {root.__name__} and its nested models.")
    return "\n".join(lines) + "\n"


def write(path: Path = PAGE) -> Path:
    text = render()
    path.parent.mkdir(parents=True, exist_ok=True)
    if not path.exists() or path.read_text() != text:
        path.write_text(text)
    return path


def setup(app):
    app.connect("builder-inited", lambda app: write())
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}


if __name__ == "__main__":
    print(write(Path(sys.argv[1]) if len(sys.argv) > 1 else PAGE))
