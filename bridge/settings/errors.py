"""What a configuration error says: one line per problem, naming the key as the file spells it.

settings/ validates; this module words pydantic's errors for the user (settings/'s
format_validation_error passes it the root model and the environment's prefix).

Rules:
1. Every line names its key with the file's spelling (``rotators[0].port``, ``mqtt.tls``), and
   the environment variable beside it where one set the value.
2. An unknown key or table names the nearest known one in the same place (difflib), or the
   tables that exist there: ``[[rotator]]`` is "did you mean [[rotators]]?". The "missing" line
   such a typo also causes for the real name is left out: the suggestion says it all.
3. The value given is never added to a line (pydantic keeps it apart, and a password could be
   one): a line holds the key, pydantic's words for what was expected, or a validator's own
   message, which quotes no secret.
4. An unknown model gets the same help as a key (``unknown_model``): the nearest model name, or,
   for a maker's name, the models that fit that maker's controllers (BRANDS), on the same line.
5. A table written with the other number of brackets (``[rotators]`` for a list of tables,
   ``[[mqtt]]`` for one table: pydantic's shape errors, _SHAPE_ERRORS) says which to write
   instead of pydantic's words ("Input should be a valid list") or a class of ours.
"""

from __future__ import annotations

import difflib
from typing import Any, get_args

from pydantic import BaseModel, ValidationError

# rule 4: a maker's name (lower case, letters and digits only) and the models that fit its
# controllers, as a user with that maker's box would read it
BRANDS = {
    "yaesu": "a Yaesu rotor through a GS-232A or GS-232B box is gs232a or gs232b (-az for "
    "azimuth only, -450 for a 450-degree rotor); a Yaesu control box with Idiom Press's "
    "RotorCard fitted is rotorcard",
    "hygain": "a Hy-Gain control box with Idiom Press's Rotor-EZ is rotorez; Hy-Gain's own "
    "DCU-1 is dcu1",
    "idiom": "Idiom Press's boards: rotorez (Rotor-EZ) or rotorcard (RotorCard)",
    "spid": "SPID controllers: rot2prog, rot1prog (azimuth only) or md01 (MD-01/02)",
    "alfa": "Alfa Radio's SPID controllers: rot2prog, rot1prog (azimuth only) or md01 (MD-01/02)",
    "satel": "the SatEL controller (VE5FP) is satel",
    "ve5fp": "the SatEL controller (VE5FP) is satel",
    "greenheron": "Green Heron's RT-21 is rt21 (one box per rotor)",
    "m2": "M2's RC2800 is rc2800 (az/el) or rc2800-az (azimuth only)",
    "k3ng": "K3NG's Arduino controller speaks GS-232: gs232b (gs232b-az for azimuth only), or "
    "easycomm2 in satellite mode",
    "satnogs": "a SatNOGS rotator controller speaks Easycomm: easycomm2 (easycomm3 with "
    "firmware that has it)",
    "prosistel": "Prosistel's D box is prosistel (azimuth) or prosistel-el (elevation; "
    "prosistel-el-a if it answers as unit A), its Combi-Track prosistel-combi",
    "combitrack": "Prosistel's Combi-Track is prosistel-combi",
}
# pydantic's words for a value of the wrong shape: a table where a list of tables belongs, or
# the other way round (rule 5)
_SHAPE_ERRORS = frozenset({"list_type", "model_type", "model_attributes_type", "dict_type"})


def describe(
    exc: ValidationError,
    root: type[BaseModel],
    env_prefix: str,
    data: dict[str, Any] | None = None,
    environ: Any = None,
) -> str:
    """One line per problem (rule 1), under "invalid configuration:"."""
    lines = []
    suggested: set[str] = set()
    for err in exc.errors():
        names = [str(p) for p in err["loc"] if not isinstance(p, int)]
        loc: list[str] = []
        for part in err["loc"]:
            if isinstance(part, int):
                loc[-1:] = [f"{loc[-1] if loc else ''}[{part}]"]
            else:
                loc.append(str(part))
        where = ".".join(loc) or "configuration"
        variable = _variable(env_prefix, err["loc"], data, environ or {})
        if err["type"] == "extra_forbidden":
            line, nearest = _unknown(root, names, where, _value_at(data, err["loc"]))
            if variable:  # not in the file: say where it came from (rule 1)
                line = line.replace(f"{where}:", f"{where} (from {variable}):", 1)
            lines.append(line)
            if nearest is not None and len(names) == 1:
                suggested.add(nearest)
            continue
        msg = err["msg"].removeprefix("Value error, ")
        if err["type"] in _SHAPE_ERRORS and err["loc"] and not isinstance(err["loc"][-1], int):
            msg = _brackets(root, names, _value_at(data, err["loc"])) or msg  # rule 5
        if err["type"] == "missing":
            msg = "missing: it has no default"
            if where == "rotators":
                msg += "; add a [[rotators]] table with id, model and port"
        lines.append(f"{where} (from {variable}): {msg}" if variable else f"{where}: {msg}")
    # a misspelt table also leaves the real one missing (rule 2)
    lines = [ln for ln in lines if not any(ln.startswith(f"{s}: missing") for s in suggested)]
    return "invalid configuration:\n  " + "\n  ".join(lines)


def unknown_model(name: str, known: list[str]) -> str:
    """The one line for a model that is not in ``known`` (rule 4): the nearest name, or the
    models for a maker's name, then every known model."""
    plain = "".join(c for c in name.lower() if c.isalnum())
    hint = next((text for brand, text in BRANDS.items() if brand in plain), None)
    if hint is None:
        close = difflib.get_close_matches(plain, known, n=1, cutoff=0.6)
        hint = f"did you mean {close[0]}?" if close else None
    after = "" if hint is None else hint + (" " if hint.endswith("?") else "; ")
    return f"unknown model {name!r}; {after}known models: {', '.join(sorted(known))}"


def _variable(
    prefix: str, loc: tuple[int | str, ...], data: dict[str, Any] | None, env: Any
) -> str | None:
    """The environment variable that set the value at ``loc``, if one did: the one named for
    ``loc``, or for a key above it whose whole value it gave (a number, a text, a list; not a
    table, which is merged with the file's): an error in a union names the branch after the
    key (``rotators[0].presets.EU.float``), and such a line named no variable (attack 18)."""
    parts = [str(p) for p in loc]
    if len(loc) >= 3 and loc[0] == "rotators" and isinstance(loc[1], int):
        rotator = _value_at(data, loc[:2])
        if not isinstance(rotator, dict) or "id" not in rotator:
            return None
        parts = ["rotators", str(rotator["id"]), *parts[2:]]
    for n in range(len(parts), 0, -1):
        wanted = (prefix + "__".join(parts[:n])).upper()
        found: str | None = next((str(k) for k in env if k.upper() == wanted), None)
        if found is not None and (n == len(parts) or not str(env[found]).lstrip().startswith("{")):
            return found
    return None


def _unknown(
    root: type[BaseModel], names: list[str], where: str, value: object
) -> tuple[str, str | None]:
    """The line for an unknown key or table, with the nearest known name in the same place."""
    model = _model_at(root, names[:-1])
    known = list(model.model_fields) if model is not None else []
    close = difflib.get_close_matches(names[-1].lower(), known, n=1, cutoff=0.6)
    nearest = close[0] if close else None
    prefix = ".".join(names[:-1])
    is_table = isinstance(value, dict) or (
        isinstance(value, list) and bool(value) and all(isinstance(v, dict) for v in value)
    )
    if is_table:
        shown = _table(where, value)
        line = f"unknown table {shown}"
        if nearest is not None:
            full = f"{prefix}.{nearest}" if prefix else nearest
            line += f": did you mean {_table(full, _shape(model, nearest))}?"
        elif model is not None:
            tables = [
                _table(f"{prefix}.{n}" if prefix else n, _shape(model, n))
                for n, f in model.model_fields.items()
                if _model_in(f.annotation) is not None
            ]
            line += f" (the tables here: {', '.join(tables)})" if tables else ""
        return line, nearest
    line = f"{where}: unknown key"
    if nearest is not None:
        line += f": did you mean {nearest}?"
    elif known:
        line += " (typo?)"
    return line, nearest


def _brackets(root: type[BaseModel], names: list[str], value: object) -> str | None:
    """Rule 5: a table written with the other number of brackets, and how to write it."""
    model = _model_at(root, names[:-1]) if names else None
    if model is None or _model_at(root, names) is None:
        return None  # not one of our tables
    many = isinstance(_shape(model, names[-1]), list)
    name = ".".join(names)
    if many and isinstance(value, dict):
        return f"written [{name}], one table; write [[{name}]], with two brackets, for each one"
    if not many and isinstance(value, list):
        return f"written [[{name}]], a list of tables; write [{name}], with one bracket, once"
    return None


def _table(name: str, value: object) -> str:
    return f"[[{name}]]" if isinstance(value, list) else f"[{name}]"


def _shape(model: type[BaseModel] | None, name: str) -> object:
    """A value shaped like the field ``name`` of ``model``: a list for an array of tables."""
    field = model.model_fields.get(name) if model is not None else None
    origin = getattr(field.annotation, "__origin__", None) if field is not None else None
    return [] if origin is list else {}


def _model_at(root: type[BaseModel], names: list[str]) -> type[BaseModel] | None:
    """The settings model whose keys are those at ``names`` (None: not a table of ours)."""
    model = root
    for name in names:
        field = model.model_fields.get(name)
        if field is None:
            return None
        inner = _model_in(field.annotation)
        if inner is None:
            return None
        model = inner
    return model


def _model_in(annotation: object) -> type[BaseModel] | None:
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in get_args(annotation):
        found = _model_in(arg)
        if found is not None:
            return found
    return None


def _value_at(data: dict[str, Any] | None, loc: tuple[int | str, ...]) -> object:
    value: object = data
    for part in loc:
        if isinstance(value, dict) and part in value:
            value = value[part]
        elif isinstance(value, list) and isinstance(part, int) and part < len(value):
            value = value[part]
        else:
            return None
    return value
