"""The model assembly and the kernel generator: layout by name, generated modules that
hold only imports and constants, a cache key that follows every source the kernel uses,
and generation that several processes can do at once."""

from __future__ import annotations

import ast
import os
import re
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

import pneumact as pa
from conftest import load_quietly
from pneumact.core import codegen
from pneumact.simulation import assemble
from reference import FRICTION_RTOL

SRC = str(Path(pa.__file__).resolve().parents[1])


@pytest.fixture
def valve_actuator(vgt):
    return pa.Actuator(vgt, valve=pa.PressureRegulator(), chamber=pa.Adiabatic())


def test_layout_is_the_components_blocks(valve_actuator):
    assembly = assemble(valve_actuator)
    roles = [part.role for part in assembly.parts]
    assert roles == ["mechanics", "friction", "valve"]
    assert assembly.state_names == ("position", "velocity", "bristle", "pressure", "opening",
                                    "integral")
    assert len(assembly.slots["A_d"]) == 2  # read by the mechanics and by the chamber
    assert len(assembly.slots["sigma0"]) == 1
    assert "k_drive" not in assembly.slots  # only what the components declare
    assert assembly.signal_source("pressure") == (0, 3)  # a state behind a valve
    assert assembly.signal_source("friction")[0] == 1  # a derived output


def test_pack_update_and_values_by_name(valve_actuator, vgt):
    assembly = assemble(valve_actuator)
    vec = assembly.pack()
    assert assembly.values(vec) == {name: vgt[name] for name in assembly.slots}
    derived = {s.name: s.index for s in assembly.entries if s.kind == "derived"}
    assert vec[derived["n_poly"]] == vgt["gamma"]  # adiabatic: n = γ
    assembly.update(vec, {"A_d": 3e-3, "gamma": 1.3})
    assert all(vec[i] == 3e-3 for i in assembly.slots["A_d"])
    assert vec[derived["n_poly"]] == 1.3  # re-derived on every change


def test_result_records_values_and_components(vgt):
    model = pa.Actuator(vgt.replace(Fc=2.5), valve=pa.CommandValve())
    r = pa.simulate(model, pa.CommandCycle(period=1.0, n_points=11))
    assert r.parameters["Fc"] == 2.5 and r.parameters["V0"] == vgt["V0"]
    assert r.components == {"mechanics": "diaphragm mechanics",
                            "friction": "LuGre(decaying_damping=False)",
                            "valve": "CommandValve"}
    assert r.to_pandas().attrs["parameters"]["Fc"] == 2.5


def test_generated_module_holds_only_imports_and_constants(valve_actuator):
    spec = assemble(valve_actuator).kernel_spec()
    tree = ast.parse(spec.source())
    for node in tree.body[1:]:  # after the docstring
        assert isinstance(node, ast.ImportFrom | ast.Assign), ast.dump(node)
        if isinstance(node, ast.Assign):
            ast.literal_eval(node.value)  # a constant, nothing computed


def test_key_covers_every_source_the_kernel_imports(valve_actuator):
    spec = assemble(valve_actuator).kernel_spec()
    names = {p.relative_to(Path(pa.__file__).parent).as_posix()
             for p in codegen.dependency_files(spec.modules())}
    for needed in ("models/friction/lugre.py", "models/friction/scalar_law.py",
                   "models/friction/base.py", "core/marks.py", "models/valves.py",
                   "models/pneumatics.py", "models/mechanics.py", "core/signals.py",
                   "core/linalg.py",
                   "core/integrators.py"):
        assert needed in names, needed
    # nothing the kernel does not use: an import inside a function binds no global that
    # compiled code reads, so it is not followed (models/friction/base.py imports the assembly
    # there, which once pulled in nearly the whole package)
    for unused in ("cli/simulate.py", "plotting.py", "identification/fit.py",
                   "core/assembly.py", "simulation/simulate.py", "io/records.py"):
        assert unused not in names, unused


def test_only_import_time_imports_are_followed(tmp_path, monkeypatch):
    source = textwrap.dedent("""
        from typing import TYPE_CHECKING
        import pneumact.errors
        try:
            from pneumact.checks import MAX_ABSOLUTE_PRESSURE
        except ImportError:
            pass
        if TYPE_CHECKING:
            from pneumact.plotting import new_axes
        class Holder:
            from pneumact.version import __version__
        def later():
            from pneumact.identification import fit
    """)
    path = tmp_path / "module.py"
    path.write_text(source)
    found = codegen.import_time_imports("pneumact.probe", path)
    assert {"pneumact.errors", "pneumact.checks", "pneumact.version"} <= found
    assert not any(m.startswith(("pneumact.plotting", "pneumact.identification"))
                   for m in found)


def test_key_changes_when_a_source_or_numba_changes(valve_actuator, tmp_path, monkeypatch):
    monkeypatch.setenv("PNEUMACT_CACHE_DIR", str(tmp_path))
    spec = assemble(valve_actuator).kernel_spec()
    extra = tmp_path / "dependency.py"
    extra.write_text("X = 1\n")
    real = codegen.dependency_files
    monkeypatch.setattr(codegen, "dependency_files", lambda modules: [*real(modules), extra])

    def key():
        codegen.kernel_key.cache_clear()
        return codegen.kernel_key(spec)

    first = key()
    assert key() == first  # remembered, and the same
    extra.write_text("X = 2\n")
    os.utime(extra, ns=(extra.stat().st_atime_ns, extra.stat().st_mtime_ns + 10**9))
    second = key()
    assert second != first
    monkeypatch.setattr(codegen, "_versions", lambda: "numba 0.0.0; python (3, 0, 0)")
    assert key() not in (first, second)
    codegen.kernel_key.cache_clear()


def test_two_processes_generate_the_same_kernel_at_once(tmp_path):
    script = textwrap.dedent("""
        import warnings, numpy as np
        import pneumact as pa
        warnings.simplefilter("ignore")
        params = pa.load_params("canudas1995")
        out = pa.CoulombViscous().evaluate(np.array([0.01, -0.02]), 0.0, params)
        print(repr(float(out["force"][0])))
    """)
    env = {**os.environ, "PNEUMACT_CACHE_DIR": str(tmp_path),
           "PYTHONPATH": os.pathsep.join(filter(None, [SRC, os.environ.get("PYTHONPATH")]))}
    procs = [subprocess.Popen([sys.executable, "-c", script], env=env, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True) for _ in range(2)]
    outputs = [p.communicate(timeout=600) for p in procs]
    expected = load_quietly("canudas1995")
    force = expected["Fc"] * np.tanh(0.01 / expected["v_reg"]) + expected["sigma2"] * 0.01
    for proc, (out, err) in zip(procs, outputs, strict=True):
        assert proc.returncode == 0, err
        assert float(out.strip()) == pytest.approx(force, rel=FRICTION_RTOL)
    generated = list(tmp_path.glob("pneumact_kernel_law_alone_coulomb_viscous_*.py"))
    assert len(generated) == 1  # one file, written once
    assert not list(tmp_path.glob(".*.tmp"))  # no temporary file left behind


def test_processes_needing_one_kernel_at_once_compile_it_once(tmp_path, monkeypatch, canudas):
    """Two processes wait on the kernel's compile lock (held here); once it is released
    one compiles, the other loads what it wrote (a numba cache hit, no compile)."""
    import fcntl
    import json

    from pneumact.core.assembly import Assembly
    from pneumact.models.friction.evaluation import _Law

    monkeypatch.setenv("PNEUMACT_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "numba"))
    module = codegen.load(Assembly(_Law(pa.Dahl(), canudas)).kernel_spec())
    script = textwrap.dedent(f"""
        import json, sys, warnings, numpy as np
        import pneumact as pa
        warnings.simplefilter("ignore")
        params = pa.load_params("canudas1995")
        print("ready", flush=True)
        pa.Dahl().evaluate(np.array([0.01, -0.02]), 0.0, params)
        stats = sys.modules[{module.__name__!r}].law_values.stats
        print(json.dumps([sum(stats.cache_misses.values()), sum(stats.cache_hits.values())]))
    """)
    env = {**os.environ,
           "PYTHONPATH": os.pathsep.join(filter(None, [SRC, os.environ.get("PYTHONPATH")]))}
    with open(codegen.compile_lock_path(module.__file__, "law_values"), "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        procs = [subprocess.Popen([sys.executable, "-c", script], env=env,
                                  stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
                 for _ in range(2)]
        assert [p.stdout.readline().strip() for p in procs] == ["ready", "ready"]
        time.sleep(1.0)  # both now wait on the lock
        fcntl.flock(lock, fcntl.LOCK_UN)
    outputs = [p.communicate(timeout=600) for p in procs]
    assert all(p.returncode == 0 for p in procs), [err for _, err in outputs]
    compiled = sorted(json.loads(out.strip().splitlines()[-1]) for out, _ in outputs)
    assert compiled == [[0, 1], [1, 0]]  # (compiles, cache hits): one each


def test_parameters_not_used_by_the_model_are_refused(canudas):
    rig = pa.FrictionRig(canudas, drive="force")
    assembly = assemble(rig)
    assert "A_d" not in assembly.slots
    with pytest.raises(pa.ParameterError, match="not a parameter of FrictionRig"):
        assembly.check_parameters(["A_d"], "table column")
    vec = assembly.pack()
    assert np.all(np.isfinite(vec))


def _templates(tmp_path, monkeypatch, **sources: str) -> None:
    """Write template modules ``name -> source`` where they can be imported."""
    for name, source in sources.items():
        (tmp_path / f"{name}.py").write_text(textwrap.dedent(source))
    monkeypatch.syspath_prepend(str(tmp_path))


MODEL = """
    from pneumact.core.codegen import kernel
    helper = None
    SCALE = 2.0
    NOUT = 7  # a placeholder: the generated module says how many outputs there are
    @kernel()
    def rhs(x):
        return SCALE * helper(x) + NOUT
"""
DRIVER = """
    from pneumact.core.codegen import kernel
    rhs = None
    OPTIONAL_FUNCTIONS = ("jump",)
    jump = None
    SCALE = {scale}
    NOUT = 1
    @kernel()
    def helper(x):
        return x + 1.0
    @kernel()
    def run(x):
        return rhs(x)
"""


@pytest.mark.parametrize("order", [("model_t", "driver_t"), ("driver_t", "model_t")])
def test_binding_does_not_depend_on_the_order(tmp_path, monkeypatch, order):
    monkeypatch.setenv("PNEUMACT_CACHE_DIR", str(tmp_path / "cache"))
    _templates(tmp_path, monkeypatch, model_t=MODEL, driver_t=DRIVER.format(scale=2.0))
    spec = codegen.KernelSpec(f"order_{order[0]}", order, (), (("NOUT", 3),))
    module = codegen.load(spec)
    assert module.run(1.0) == 2.0 * 2.0 + 3  # NOUT from the generated module
    assert module.jump is None  # optional, and nobody defines it


def test_a_name_two_templates_define_differently_is_refused(tmp_path, monkeypatch):
    monkeypatch.setenv("PNEUMACT_CACHE_DIR", str(tmp_path / "cache"))
    _templates(tmp_path, monkeypatch, model_c=MODEL, driver_c=DRIVER.format(scale=3.0))
    spec = codegen.KernelSpec("clash", ("model_c", "driver_c"), (), (("NOUT", 3),))
    with pytest.raises(pa.PneumactError, match="driver_c and model_c both define 'SCALE'"):
        codegen.load(spec)


def test_a_function_nobody_defines_is_named(tmp_path, monkeypatch):
    monkeypatch.setenv("PNEUMACT_CACHE_DIR", str(tmp_path / "cache"))
    _templates(tmp_path, monkeypatch, model_m=MODEL)
    spec = codegen.KernelSpec("missing", ("model_m",), (), (("NOUT", 3),))
    with pytest.raises(pa.PneumactError, match="model_m needs 'helper'"):
        codegen.load(spec)


def test_output_indices_are_generated_from_the_names(valve_actuator):
    assembly = assemble(valve_actuator)
    constants = dict(assembly.kernel_spec().constants)
    assert constants["NOUT"] == len(assembly.output_names)
    for i, name in enumerate(assembly.output_names):
        assert constants[f"OUT_{name.upper()}"] == i
    # and no template numbers an output by hand
    templates = Path(codegen.__file__).with_name("templates")
    for path in templates.glob("*.py"):
        # (the integrators' O_* are slots of their own info array, not outputs)
        hand = re.findall(r"^(?:NOUT|OUT_\w+) = \d+", path.read_text(), re.M)
        if path.name != "integrators.py":
            hand += re.findall(r"^O_\w+ = \d+", path.read_text(), re.M)
        assert not hand, (path.name, hand)
