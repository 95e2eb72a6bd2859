"""The command line speaks the API's words (issue 20, item 5): every option of every
command is a parameter of a function the command calls, or a field of an object it
builds, with the same default; the mapping is declared once, in ``pneumact.cli.api``.

An option that maps onto nothing fails with its command and name; a default that
differs from the API's fails with both values. A default of None on the command line
means "not given: the API (or the plant) decides", so it matches any API default.
"""

from __future__ import annotations

import dataclasses
import importlib
import inspect
import math
import typing
from pathlib import Path

import pytest

EMPTY = inspect.Parameter.empty


def _commands() -> dict[str, object]:
    """Every leaf command of the ``pneumact`` application, by its words."""
    import typer

    from pneumact.cli import app

    found: dict[str, object] = {}

    def walk(command, words: list[str]) -> None:
        children = getattr(command, "commands", None)
        if children is None:
            found[" ".join(words)] = command
            return
        for name, child in children.items():
            walk(child, [*words, name])

    walk(typer.main.get_command(app), [])
    return found


def _load(spec: str):
    module, _, name = spec.partition(":")
    target = importlib.import_module(module)
    for part in name.split("."):
        target = getattr(target, part)
    return target


def _option_classes(function) -> list[type]:
    """The option objects (``pneumact.options``) a function takes."""
    import pneumact.options as options

    classes = [getattr(options, n) for n in options.__all__
               if isinstance(getattr(options, n), type)]
    try:
        hints = typing.get_type_hints(inspect.unwrap(function))
    except Exception:  # an annotation that does not resolve: no option objects
        return []
    found = []
    for hint in hints.values():
        for arg in (*typing.get_args(hint), hint):
            if isinstance(arg, type) and arg in classes and arg not in found:
                found.append(arg)
    return found


def _field_defaults(cls: type) -> dict[str, object]:
    out = {}
    for f in dataclasses.fields(cls):
        if f.default is not dataclasses.MISSING:
            out[f.name] = f.default
        elif f.default_factory is not dataclasses.MISSING:
            out[f.name] = f.default_factory()
        else:
            out[f.name] = EMPTY
    return out


def api_parameters(target) -> dict[str, object]:
    """name -> default (``EMPTY``: none) of a function's parameters and of the fields of
    the option objects it takes; of a class's fields (or constructor)."""
    if isinstance(target, type) and dataclasses.is_dataclass(target):
        return _field_defaults(target)
    signature = inspect.signature(target)
    out = {name: p.default for name, p in signature.parameters.items()
           if p.kind not in (p.VAR_KEYWORD, p.VAR_POSITIONAL)}
    if not isinstance(target, type):
        for cls in _option_classes(target):
            for name, default in _field_defaults(cls).items():
                out.setdefault(name, default)
    return out


def _plain(value):
    """A default as the command line writes it: an enum choice its value, a strategy
    object (valve, friction law, chamber law) its --choice name."""
    value = getattr(value, "value", value)
    if isinstance(value, Path):
        return str(value)
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return getattr(value, "cli_name", type(value).__name__.lower())
    return value


def same_default(cli, api, factor: float = 1.0, inverted: bool = False,
                 none_means: object = None) -> bool:
    if api is EMPTY or cli is None:
        return True
    if api is None and none_means is not None:
        api = none_means
    cli, api = _plain(cli), _plain(api)
    if inverted:
        return isinstance(cli, bool) and cli is (not api)
    if isinstance(cli, bool) or isinstance(api, bool):
        return cli is api
    if isinstance(cli, int | float) and isinstance(api, int | float):
        return math.isclose(cli * factor, api, rel_tol=1e-12)
    if isinstance(cli, str) and isinstance(api, tuple | list):  # a comma-separated list
        return [s for s in cli.split(",") if s] == [str(a) for a in api]
    return cli == api


def option_problems() -> list[str]:
    """Every option that maps onto nothing, or whose default differs from the API's."""
    from pneumact.cli.api import API, NONE_MEANS, OWN, SPELLED, UNITS

    problems = []
    commands = _commands()
    missing = sorted(set(commands) - set(API) - {""})
    problems += [f"{c}: the command has no entry in pneumact.cli.api.API" for c in missing]
    for words, command in commands.items():
        params = {}
        for spec in API.get(words, ()):
            for name, default in api_parameters(_load(spec)).items():
                params.setdefault(name, default)
        for option in command.params:  # type: ignore[attr-defined]
            if option.param_type_name != "option" or getattr(option, "hidden", False):
                continue
            flag = max(option.opts, key=len)
            word = flag.lstrip("-").replace("-", "_")
            name = option.name
            if word in OWN:
                continue
            if word != name:
                problems.append(f"{words}: {flag} sets the parameter {name!r}: the option's "
                                "word must be the parameter's")
                continue
            factor = UNITS.get(name, 1.0)
            if name in params:
                api = params[name]
                if not same_default(option.default, api, factor,
                                    none_means=NONE_MEANS.get(name)):
                    problems.append(f"{words}: {flag} defaults to {option.default!r}, the "
                                    f"API's {name} to {api!r}" + (f" (× {factor:g})" if
                                                                  factor != 1.0 else ""))
                continue
            if name in SPELLED:
                spec = SPELLED[name].lstrip("!")
                module_name, _, path = spec.partition(":")
                owner, _, parameter = path.partition(".")
                try:
                    target = _load(f"{module_name}:{owner}")
                except (ImportError, AttributeError):
                    problems.append(f"{words}: {flag} is spelled as {spec}, which does "
                                    "not exist")
                    continue
                if parameter:
                    known = api_parameters(target)
                    if parameter not in known:
                        problems.append(f"{words}: {flag} is spelled as {spec}, which "
                                        "does not exist")
                    elif not same_default(option.default, known[parameter], factor,
                                          inverted=SPELLED[name].startswith("!")):
                        problems.append(f"{words}: {flag} defaults to "
                                        f"{option.default!r}, {spec} to "
                                        f"{known[parameter]!r}")
                continue
            problems.append(f"{words}: {flag} maps onto no parameter of "
                            f"{', '.join(API.get(words, ())) or 'anything'}")
    return problems


def test_every_option_is_an_api_parameter_with_its_default():
    problems = option_problems()
    assert not problems, "\n".join(problems)


def test_the_declared_targets_exist():
    from pneumact.cli.api import API, SPELLED

    for words, specs in API.items():
        for spec in specs:
            assert _load(spec) is not None, (words, spec)
    for name, spec in SPELLED.items():
        module_name, _, path = spec.lstrip("!").partition(":")
        assert _load(f"{module_name}:{path.partition('.')[0]}") is not None, name


@pytest.mark.parametrize(("cli", "api", "factor", "same"), [
    (20.0, 20e3, 1e3, True), (21.0, 20e3, 1e3, False), (None, 5.0, 1.0, True),
    ("position", ("position",), 1.0, True), ("a,b", ("a",), 1.0, False),
    (False, True, 1.0, False), (0, 0.0, 1.0, True)])
def test_defaults_are_compared_in_the_api_units(cli, api, factor, same):
    assert same_default(cli, api, factor) is same


def test_chamber_laws_and_friction_options_are_reachable():
    """--chamber polytropic --exponent and --decaying-damping build the API's objects
    (the options ``simulate``, ``simulate-batch``, ``fit``, ``sensitivity`` and
    ``validate`` share)."""
    import pneumact as pa
    from conftest import load_quietly
    from pneumact.cli.common import Chamber, ModelOptions, Valve, build_cylinder, build_model
    from pneumact.errors import ArgumentError

    options = ModelOptions(valve=Valve.command, chamber=Chamber.polytropic, exponent=1.3,
                           decaying_damping=True)
    _, actuator = build_model(options, load_quietly("vgt-paper"))
    assert actuator.chamber == pa.Polytropic(1.3)
    assert actuator.friction == pa.LuGre(decaying_damping=True)
    for chamber in Chamber:  # every chamber law of the API has its choice
        options = ModelOptions(valve=Valve.command, chamber=chamber)
        if chamber is Chamber.heat_transfer:  # the cylinder's chambers alone
            with pytest.raises(ArgumentError, match="--model cylinder"):
                build_model(options, load_quietly("vgt-paper"))
            model = build_cylinder(ModelOptions(chamber=chamber))[1]
        else:
            model = build_model(options, load_quietly("vgt-paper"))[1]
        assert type(model.chamber).__name__.lower() == chamber.value.replace("-", "")
    with pytest.raises(ArgumentError, match=r"--exponent 1\.3 is the exponent of --chamber "
                                            "polytropic"):
        build_model(ModelOptions(valve=Valve.command, exponent=1.3))
    with pytest.raises(ArgumentError, match="--decaying-damping is an option of --friction "
                                            "lugre"):
        build_model(ModelOptions(friction="dahl", decaying_damping=True))


def test_elements_builds_a_gms_law_and_a_set_without_its_blocks_names_one_with_them():
    """--friction gms --elements N is GMS(n_elements=N); a set without the blocks is
    refused naming the shipped set that has them; --elements goes with gms only."""
    import pneumact as pa
    from conftest import load_quietly
    from pneumact.cli.common import ModelOptions, build_model
    from pneumact.errors import ArgumentError

    _, actuator = build_model(ModelOptions(friction="gms", elements=3),
                              load_quietly("vgt-paper-gms4"))
    assert actuator.friction == pa.GMS(n_elements=3)
    with pytest.raises(ArgumentError, match=r"lacks gms_C.*shipped sets that have them: "
                                            r"vgt-paper-gms4"):
        build_model(ModelOptions(friction="gms", elements=4), load_quietly("vgt-paper"))
    with pytest.raises(ArgumentError, match="--elements is an option of --friction gms"):
        build_model(ModelOptions(friction="dahl", elements=4), load_quietly("vgt-paper"))
    assert build_model(ModelOptions(friction="elasto-plastic"),
                       load_quietly("vgt-paper"))[1].friction == pa.ElastoPlastic()
