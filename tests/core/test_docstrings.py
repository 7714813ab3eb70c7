"""The public API's docstrings, checked by numpydoc's own validation: every name ``import
maizeviz as mv`` exports, and the public methods and properties of its classes, document
every parameter and what they return in numpydoc's sections; a parameter named with a unit
states it in brackets ("[cm]"); References carry DOIs."""

from __future__ import annotations

import inspect
import re

import pytest

numpydoc_validate = pytest.importorskip("numpydoc.validate")

import maizeviz as mv  # noqa: E402

#: numpydoc checks not asked of every name: an extended summary, See Also and Examples
#: sections (the package's example is a doctest of its own).
OPTIONAL = {"ES01", "SA01", "EX01"}
#: Parameter names that carry a unit: their description says it in brackets.
UNIT_NAMES = re.compile(r"(_cm|_cm2|_m|_m2|_deg|_w_m2|_min|_s|_mol|_j|_mj|_sr)$|^(lat|lon|"
                        r"altitude|zenith|azimuth|density|threshold|linke|par_factor)$")


def exported() -> list[tuple[str, object]]:
    """Import paths and objects of every exported callable and class, and of the public
    methods and properties its classes define or inherit from maizeviz."""
    out = []
    for name in mv.__all__:
        obj = getattr(mv, name)
        if not (callable(obj) or inspect.isclass(obj)):
            continue                             # constants: described by the module
        out.append((f"maizeviz.{name}", obj))
        if not inspect.isclass(obj) or issubclass(obj, BaseException):
            continue
        for cls in obj.__mro__:
            if not cls.__module__.startswith("maizeviz"):
                continue
            for attr, member in vars(cls).items():
                if attr.startswith("_") or any(attr in vars(c) for c in obj.__mro__[
                        :obj.__mro__.index(cls)]):
                    continue                     # private, or overridden below
                if callable(member) or isinstance(member, property) or \
                        hasattr(member, "__set_name__"):
                    out.append((f"{cls.__module__}.{cls.__qualname__}.{attr}", member))
    return out


NAMES = [path for path, _ in exported()]


def test_every_exported_name_is_checked():
    assert len(NAMES) > 60
    assert "maizeviz.LightEngine" in NAMES
    assert "maizeviz.light.engine.LightEngine.absorbed_day" in NAMES
    assert "maizeviz.light.results.traced.TracedLight.table" in NAMES


@pytest.mark.parametrize("path", NAMES)
def test_numpydoc_validation_passes(path):
    report = numpydoc_validate.validate(path)
    errors = [f"{code} {text}" for code, text in report["errors"] if code not in OPTIONAL]
    assert not errors, f"{path}: " + "; ".join(errors)


@pytest.mark.parametrize("path", NAMES)
def test_units_in_brackets_and_references_with_dois(path):
    from numpydoc.docscrape import NumpyDocString

    report = numpydoc_validate.validate(path)
    doc = NumpyDocString(report["docstring"] or "")
    for p in doc["Parameters"]:
        for name in (n.strip().lstrip("*") for n in p.name.split(",")):
            if UNIT_NAMES.search(name):
                assert "[" in " ".join(p.desc), f"{path}: {name} states no unit in brackets"
    refs = " ".join(doc["References"])
    if refs.strip():
        assert "https://doi.org/10." in refs, f"{path}: References without a DOI"
