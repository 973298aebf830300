"""The generated scene-key reference (docs/_ext/scene_keys.py) covers the schema."""

import importlib.util
import inspect
import sys
import typing
from pathlib import Path

import pytest
from pydantic import BaseModel

GENERATOR = Path(__file__).resolve().parents[1] / "docs" / "_ext" / "scene_keys.py"


@pytest.fixture(scope="module")
def scene_keys():
    spec = importlib.util.spec_from_file_location("scene_keys", GENERATOR)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


def _models(annotation):
    """The pydantic models an annotation holds (through Annotated, unions and lists)."""
    while typing.get_origin(annotation) is typing.Annotated:
        annotation = typing.get_args(annotation)[0]
    if inspect.isclass(annotation) and issubclass(annotation, BaseModel):
        return [(annotation, "")]
    out = []
    for arg in typing.get_args(annotation):
        inner = _models(arg)
        suffix = "[]" if typing.get_origin(annotation) is list else ""
        out += [(m, suffix + s) for m, s in inner]
    return out


def schema_fields(model, prefix=""):
    """(key path, field) of every field of the schema, walked independently of the
    generator."""
    out = []
    for name, field in model.model_fields.items():
        path = prefix + name
        out.append((path, field))
        for sub, suffix in _models(field.annotation):
            out += schema_fields(sub, f"{path}{suffix}.")
    return out


def test_reference_covers_every_schema_field(scene_keys):
    schema = scene_keys.schema_class()
    expected = {path for path, _ in schema_fields(schema)}
    generated = {k.path for k in scene_keys.walk()}
    assert generated == expected
    page = scene_keys.render()
    missing = [p for p in sorted(expected) if f"| `{p}` |" not in page]
    assert not missing, f"keys missing from the rendered page: {missing}"


def test_every_field_has_a_description(scene_keys):
    """Fails until each field of the schema has a pydantic `description` (the reference
    shows the source comment until then)."""
    schema = scene_keys.schema_class()
    undescribed = [path for path, field in schema_fields(schema)
                   if not (field.description or "").strip()]
    assert not undescribed, f"{len(undescribed)} fields without a description: {undescribed}"
