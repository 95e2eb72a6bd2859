"""Kernel generation: one compiled module per model × component combination.

Numba caches compiled code on disk per source file, but not for closures or for
functions passed as arguments, so components cannot be composed at run time without
recompiling in every process. Instead, for each combination a small module is generated
that holds only imports (the chosen component functions under the names a template
calls: ``friction_law``, ``valve_rates``, …) and constants (the layout of the state and
parameter vectors). The functions of the templates (a model's ``*_template.py`` beside
it, ``core/integrators.py``; marked with ``@kernel``) are then
bound to that module's namespace and compiled with ``cache=True``: numba keys their
disk cache on the generated file, so each combination compiles once per machine and
loads from disk afterwards. Parameter values are a runtime array: changing them never
recompiles.

The generated file's name carries a key over its own text, every pneumact source file
the kernel depends on (found by following the module-level imports of the templates and
of the component modules, not from a list kept by hand: an import inside a function
binds no global that compiled code reads), and the numba and Python versions. An edit
to the CLI, a plot or the identification therefore recompiles nothing.
Files are created atomically and only if absent, so several processes may generate the
same kernel at once.
"""

from __future__ import annotations

import ast
import contextlib
import functools
import hashlib
import importlib
import importlib.util
import json
import os
import sys
import tempfile
import threading
import types
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .compile_lock import compile_one_process_at_a_time
from .marks import kernel

__all__ = ["Child", "KernelSpec", "cache_dir", "compile_lock_path", "content_key",
           "dependency_files", "import_time_imports", "kernel", "kernel_key", "load"]

#: a template's tuple of the placeholders it can do without (called only under a switch)
OPTIONAL = "OPTIONAL_FUNCTIONS"

_LOCK = threading.RLock()
_LOADED: dict[str, types.ModuleType] = {}
_PACKAGE = "pneumact"


@dataclass(frozen=True)
class KernelSpec:
    """What a generated kernel module holds.

    ``templates``: modules whose ``@kernel`` functions are bound into it; ``imports``:
    (alias, "module:attribute") pairs; ``constants``: (name, value) pairs of ints,
    floats, bools or tuples of them. ``label`` names the combination in the file name.
    ``components``: the components' own templates (a friction law's functions on its
    slice of the state), bound first, so that the model's templates and its children
    (a closed loop's plant) call them.
    """

    label: str
    templates: tuple[str, ...]
    imports: tuple[tuple[str, str], ...]
    constants: tuple[tuple[str, object], ...]
    children: tuple[Child, ...] = ()
    components: tuple[str, ...] = ()

    def source(self) -> str:
        """Text of the generated module: a docstring, imports and constants."""
        lines = [f'"""pneumact kernel {self.label}: generated, do not edit.',
                 "", f"Templates bound to it: {', '.join((*self.components, *self.templates))}."]
        lines += [f"Bound under '{c.prefix}': the kernel {module_name(c.spec)}."
                  for c in self.children]
        lines.append('"""')
        for alias, target in self.imports:
            module, attribute = target.split(":")
            lines.append(f"from {module} import {attribute} as {alias}")
        for name, value in self.constants:
            lines.append(f"{name} = {value!r}")
        return "\n".join(lines) + "\n"

    def modules(self) -> tuple[str, ...]:
        """The modules the kernel's code comes from (templates and component modules)."""
        imported = (target.split(":")[0] for _, target in self.imports)
        children = (m for c in self.children for m in c.spec.modules())
        return tuple(dict.fromkeys((*self.components, *self.templates, *children,
                                    *imported)))


@dataclass(frozen=True)
class Child:
    """Another model's own kernel, its functions exposed under ``prefix``.

    A closed loop calls its plant's kernel this way: the plant's ``rhs`` becomes
    ``plant_rhs`` beside the loop's own ``rhs``. The plant's states come first in the
    loop's state vector and its parameter blocks first in the loop's vector, so the
    plant's code reads both where it always does. The functions are the plant kernel's
    own (the same compiled code as an open-loop run of the plant): every controller
    configuration over one plant shares them, compiled once per machine.
    """

    prefix: str
    spec: KernelSpec


def cache_dir() -> Path:
    """Where generated kernels and their compiled code live (``PNEUMACT_CACHE_DIR``)."""
    env = os.environ.get("PNEUMACT_CACHE_DIR")
    if env:
        return Path(env)
    from platformdirs import user_cache_dir

    return Path(user_cache_dir("pneumact")) / "kernels"


# --------------------------------------------------------------------------- dependencies
def _module_file(name: str) -> Path | None:
    """Source file of pneumact module ``name`` (None when ``name`` is not a module), found
    in the package directory without importing anything."""
    root = Path(__file__).resolve().parents[1]  # the pneumact package directory
    parts = name.split(".")[1:]
    candidates = [root.joinpath(*parts).with_suffix(".py"), root.joinpath(*parts, "__init__.py")]
    if not parts:
        candidates = [root / "__init__.py"]
    return next((path for path in candidates if path.is_file()), None)


def _import_time_statements(body: list[ast.stmt]) -> Iterable[ast.stmt]:
    """The statements of a module that run when it is imported: its body, through
    ``if``/``try``/``with`` blocks and class bodies, but not function bodies (an import
    inside a function cannot bind a global that compiled code reads) nor
    ``if TYPE_CHECKING:`` blocks."""
    for node in body:
        yield node
        if isinstance(node, ast.If):
            test = node.test
            checking = (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
                isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")
            if not checking:
                yield from _import_time_statements(node.body)
            yield from _import_time_statements(node.orelse)
        elif isinstance(node, ast.Try):
            for block in (node.body, node.orelse, node.finalbody,
                          *(handler.body for handler in node.handlers)):
                yield from _import_time_statements(block)
        elif isinstance(node, (ast.With, ast.ClassDef)):
            yield from _import_time_statements(node.body)


def import_time_imports(name: str, path: Path) -> set[str]:
    """pneumact modules imported by the module ``name`` when it is imported (absolute and
    relative imports at module level: see ``_import_time_statements``)."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found: set[str] = set()
    for node in _import_time_statements(tree.body):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = package.split(".")
                parts = parts[: len(parts) - node.level + 1]
                base = ".".join(p for p in (*parts, base) if p)
            found.add(base)
            found.update(f"{base}.{alias.name}" for alias in node.names)
    return {m for m in found if m == _PACKAGE or m.startswith(_PACKAGE + ".")}


def dependency_files(modules: Iterable[str]) -> list[Path]:
    """Every pneumact source file reachable by import-time imports from ``modules``
    (sorted): the code that can reach a kernel built from them."""
    return list(_dependency_closure(tuple(sorted(modules))))


@functools.cache
def _dependency_closure(modules: tuple[str, ...]) -> tuple[Path, ...]:
    seen: dict[str, Path] = {}
    todo = list(modules)
    while todo:
        name = todo.pop()
        if name in seen:
            continue
        path = _module_file(name)
        if path is None:
            continue  # an attribute imported with "from x import y", not a module
        seen[name] = path
        todo.extend(import_time_imports(name, path) - set(seen))
    return tuple(sorted(set(seen.values())))


def _versions() -> str:
    from importlib.metadata import version

    return f"numba {version('numba')}; python {sys.version_info[:3]}"


def _stamps(paths: Iterable[Path]) -> list[list]:
    return [[str(p), p.stat().st_mtime_ns, p.stat().st_size] for p in paths]


@functools.cache
def kernel_key(spec: KernelSpec) -> str:
    """Hex digest over the generated text, the dependency sources and the versions.

    The digest is remembered in the cache directory with the files' modification times
    and sizes, so a later process only checks those (no reading, no parsing) unless a
    source has changed.
    """
    text = spec.source()
    # the memo is per source tree: checkouts sharing one cache must not read each other's
    # keys (their stamps would match their own files, not this tree's)
    tree = str(Path(__file__).resolve().parents[1])
    memo_id = hashlib.sha256(f"{text}\n{tree}".encode()).hexdigest()[:16]
    memo = cache_dir() / f".{spec.label}-{memo_id}.key"
    try:
        saved = json.loads(memo.read_text(encoding="utf-8"))
        if saved["versions"] == _versions() and saved["stamps"] == _stamps(
                Path(p) for p, _, _ in saved["stamps"]):
            return saved["key"]
    except (OSError, ValueError, KeyError, TypeError):
        pass
    files = _key_files(spec)
    digest = _content_digest(text, files)
    digest.update(_versions().encode())
    key = digest.hexdigest()
    with contextlib.suppress(OSError):
        memo.parent.mkdir(parents=True, exist_ok=True)
        tmp = memo.with_name(f"{memo.name}.{os.getpid()}.tmp")
        tmp.write_text(json.dumps({"key": key, "versions": _versions(),
                                   "stamps": _stamps(files)}), encoding="utf-8")
        os.replace(tmp, memo)
    return key


def content_key(spec: KernelSpec) -> str:
    """Hex digest over the generated text and the dependency sources, without the numba
    and Python versions ``kernel_key`` adds: what a kernel's code is made of, the same on
    every machine (the shipped C, ``core.c_shipped``, is found by it)."""
    return _content_digest(spec.source(), _key_files(spec)).hexdigest()


def _key_files(spec: KernelSpec) -> list[Path]:
    # the generator itself decides how the kernel is compiled (options, binding)
    return [*dependency_files(spec.modules()), Path(__file__).resolve()]


def _content_digest(text: str, files: Iterable[Path]) -> Any:
    digest = hashlib.sha256(text.encode())
    for path in files:
        digest.update(path.name.encode())
        digest.update(path.read_bytes())
    return digest


# --------------------------------------------------------------------------- loading
def _write_once(path: Path, text: str) -> None:
    """Create ``path`` with ``text`` unless it exists; atomic, and safe when several
    processes try at once (the first link wins, the others find the file)."""
    if path.exists():
        return
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
        with contextlib.suppress(FileExistsError):
            os.link(tmp, path)
    finally:
        os.unlink(tmp)


def _same(a: object, b: object) -> bool:
    """Whether two template globals are the same thing (one object, or equal constants)."""
    if a is b:
        return True
    try:
        return type(a) is type(b) and bool(a == b)
    except (TypeError, ValueError):  # e.g. arrays: only the same object is the same
        return False


def _bind(namespace: dict, template: types.ModuleType, filename: str,
          provided: frozenset[str], origins: dict[str, str], needs: dict[str, str],
          prefix: str = "") -> None:
    """Bind ``template``'s ``@kernel`` functions to the generated namespace, compiled
    with disk caching, with the template's other globals beside them.

    A global the generated module ``provided`` (its imports and constants: the layout,
    the chosen components) is the template's placeholder and is not copied. A global
    set to None is a placeholder for a function another template defines: it is
    recorded in ``needs`` (name -> template; ``_verify_needs`` checks them once all are
    bound) unless the template lists it in ``OPTIONAL_FUNCTIONS``. Any other global is
    copied; if another template bound before it holds a different value under that
    name, which one a kernel function would read depends on the binding order, so that
    is refused naming both (``origins``: name -> template that defined it).
    """
    from ..errors import PneumactError
    from .jit import lazy_dispatcher

    marked = {name: obj for name, obj in vars(template).items()
              if getattr(obj, "__kernel_options__", None) is not None
              and getattr(obj, "__module__", None) == template.__name__}
    optional = set(getattr(template, OPTIONAL, ()))
    for name, obj in vars(template).items():
        if name.startswith("__") or name in marked or name in provided or name == OPTIONAL:
            continue
        if obj is None:  # a placeholder: another template or a component defines it
            if name in optional:  # ... or nobody, and the template does without it
                namespace.setdefault(name, None)
            else:
                needs.setdefault(name, template.__name__)
            continue
        if name in namespace and not _same(namespace[name], obj):
            raise PneumactError(
                f"kernel {namespace['__name__']}: {template.__name__} and "
                f"{origins.get(name, 'the generated module')} both define {name!r} with "
                f"different values; a name the templates share must be generated (a "
                f"constant of the kernel spec) or defined once")
        if name not in namespace:
            namespace[name] = obj
            origins[name] = template.__name__
    for name, fn in marked.items():
        if name in origins:
            raise PneumactError(f"kernel {namespace['__name__']}: {template.__name__} and "
                                f"{origins[name]} both define the kernel function {name!r}")
        code = fn.__code__.replace(co_filename=filename)
        bound = types.FunctionType(code, namespace, name, fn.__defaults__, fn.__closure__)
        bound.__qualname__ = f"{template.__name__.rpartition('.')[2]}.{fn.__qualname__}"
        bound.__module__ = namespace["__name__"]
        bound.__doc__ = fn.__doc__
        options = dict(fn.__kernel_options__)
        if name.startswith("_"):  # called from compiled code only: no Python wrapper
            options.setdefault("no_cpython_wrapper", True)
        lock = compile_lock_path(filename, prefix + name)
        namespace[name] = lazy_dispatcher(
            bound, {"cache": True, **options},
            prepare=functools.partial(compile_one_process_at_a_time, lock_path=lock))
        origins[name] = template.__name__


def compile_lock_path(filename: str, function: str) -> Path:
    """The lock one kernel function compiles under (``core.compile_lock``): a hidden file
    beside the kernel module, per function, so that different functions of one kernel
    still compile at once in different processes."""
    path = Path(filename)
    return path.with_name(f".{path.stem}.{function}.lock")


def _verify_needs(namespace: dict, needs: dict[str, str]) -> None:
    """Every placeholder a template declared is defined by now (by another template, a
    child or a component); else name it and the template that needs it."""
    from ..errors import PneumactError

    missing = sorted(name for name in needs if namespace.get(name) is None)
    if missing:
        raise PneumactError(
            f"kernel {namespace['__name__']}: " + "; ".join(
                f"{needs[name]} needs {name!r}, which no template, child or component "
                "of this model defines" for name in missing))


def _bind_child(namespace: dict, child: Child) -> None:
    """Export the compiled functions of ``child.spec``'s kernel to ``namespace`` under
    ``child.prefix``."""
    module = load(child.spec)
    for template in (*child.spec.components, *child.spec.templates):
        for name, obj in vars(importlib.import_module(template)).items():
            if getattr(obj, "__kernel_options__", None) is not None and \
                    getattr(obj, "__module__", None) == template:
                namespace[child.prefix + name] = getattr(module, name)


def module_name(spec: KernelSpec) -> str:
    """The name of ``spec``'s generated module: its label and key."""
    return f"pneumact_kernel_{spec.label}_{kernel_key(spec)[:16]}"


def load(spec: KernelSpec) -> types.ModuleType:
    """The kernel module of ``spec``: generated on first use, then cached on disk and in
    this process."""
    name = module_name(spec)
    with _LOCK:
        module = _LOADED.get(name)
        if module is not None:
            return module
        folder = cache_dir()
        folder.mkdir(parents=True, exist_ok=True)
        path = folder / f"{name}.py"
        _write_once(path, spec.source())
        module_spec = importlib.util.spec_from_file_location(name, path)
        if module_spec is None or module_spec.loader is None:
            raise ImportError(f"cannot load the generated kernel module {path}")
        module = importlib.util.module_from_spec(module_spec)
        module_spec.loader.exec_module(module)
        provided = frozenset([*(alias for alias, _ in spec.imports),
                              *(name for name, _ in spec.constants)])
        origins: dict[str, str] = {}
        needs: dict[str, str] = {}
        for template in spec.components:
            _bind(module.__dict__, importlib.import_module(template), str(path), provided,
                  origins, needs)
        for child in spec.children:
            _bind_child(module.__dict__, child)
        for template in spec.templates:
            _bind(module.__dict__, importlib.import_module(template), str(path), provided,
                  origins, needs)
        _verify_needs(module.__dict__, needs)
        sys.modules[name] = module
        _LOADED[name] = module
        return module
