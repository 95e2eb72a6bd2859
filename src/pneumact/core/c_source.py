"""The kernel generator's second back end: C99 source from the compiled kernel functions.

A kernel's functions (the model template's ``rhs``, ``outputs``, ``jac``, … and every
component function they call) are written once, in the numba subset of Python. The first
back end is numba itself. This one reads what numba made of them — its typed
intermediate representation, after inlining, with every variable's type resolved — and
writes each function as a C function: one ``goto`` label per basic block, one C variable
per IR variable, tuples as structs, arrays as a (data, shape, strides) struct. So the
C code and the compiled kernels come from the same component equations, and a change
to a component changes both.

What it covers is what the kernels and the integrator driver (``core/integrators.py``)
use: float and integer scalars and their arithmetic with Python's semantics (floor
division and modulo, negative indices), ``math`` functions, ``abs``/``min``/``max``/``int``
/``float``, tuples (a homogeneous one indexed at run time too), ``range`` loops, arrays of
any dimension and their row views (``a[i]``), global arrays (constants), ``x is None``
where the types decide it (numba prunes an argument that is None), calls between compiled
functions, and arrays a function allocates (``np.empty``/``zeros``/``full``, ``a.copy()``):
those live in an arena (``pa_arena``) that a function which allocates takes as its first
parameter, down to its entry point; the caller resets the arena between calls (the memory
is kept) and frees it at the end. Anything else is refused with the construct and the
function named (``CSourceError``), never translated approximately.

Nothing is compiled to machine code on the way: numba types a call of a compiled
function by compiling that function, so the functions a root calls are typed through
typing-only stand-ins of their dispatchers (``_TypingOnly``, in copies of their
namespaces), each function once per argument types; the C is the same as when numba
compiles them.
"""

from __future__ import annotations

import builtins
import itertools
import math
import operator
import re
import threading
import types as pytypes
from collections import OrderedDict
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numba
import numpy as np
from numba.core import ir, registry, sigutils, types
from numba.core.compiler import CompilerBase, DefaultPassBuilder, Flags, compile_extra
from numba.core.compiler_machinery import FunctionPass, PassManager, register_pass
from numba.core.typed_passes import AnnotateTypes
from numba.core.typing.templates import signature

from .c_abi import Arena, array_struct, c_array
from .c_build import CSourceError
from .jit import dispatcher_of, is_compiled_function

__all__ = ["Arena", "CSourceError", "CUnit", "array_struct", "c_array", "translate"]


BINARY = {operator.add: "+", operator.sub: "-", operator.mul: "*", operator.lt: "<",
          operator.le: "<=", operator.gt: ">", operator.ge: ">=", operator.eq: "==",
          operator.ne: "!=", operator.and_: "&", operator.or_: "|", operator.xor: "^",
          operator.iadd: "+", operator.isub: "-", operator.imul: "*",
          operator.lshift: "<<", operator.rshift: ">>"}
UNARY = {operator.neg: "-", operator.pos: "+", operator.not_: "!", operator.invert: "~"}
#: math and numpy scalar functions with a C99 <math.h> function of the same meaning
MATH = {"exp": "exp", "log": "log", "log10": "log10", "log1p": "log1p", "expm1": "expm1",
        "sqrt": "sqrt", "sin": "sin", "cos": "cos", "tan": "tan", "asin": "asin",
        "acos": "acos", "atan": "atan", "atan2": "atan2", "sinh": "sinh", "cosh": "cosh",
        "tanh": "tanh", "fabs": "fabs", "floor": "floor", "ceil": "ceil", "pow": "pow",
        "hypot": "hypot", "copysign": "copysign", "isfinite": "isfinite", "isnan": "isnan",
        "isinf": "isinf", "erf": "erf", "erfc": "erfc", "cbrt": "cbrt",
        "absolute": "fabs", "power": "pow", "arctan": "atan", "arctan2": "atan2",
        "arcsin": "asin", "arccos": "acos", "trunc": "trunc"}

#: the arena's type and functions, declared in the header too (its user resets and frees it)
ARENA_TYPES = r"""
typedef struct pa_chunk pa_chunk;
typedef struct { pa_chunk *first, *current; int failed; } pa_arena;
"""
ARENA_FUNCTIONS = "void pa_arena_reset(pa_arena *m);\nvoid pa_arena_free(pa_arena *m);"
#: numpy functions that allocate an array (its dtype is the target's type)
ALLOCATORS = ("empty", "zeros", "full")

PRELUDE = r"""
#include <math.h>
#include <stdint.h>
#include <stdlib.h>

#if defined(__GNUC__)
#define PA_INLINE static inline __attribute__((always_inline))
#else
#define PA_INLINE static inline
#endif

typedef struct { int64_t start, stop, step; } pa_range;
typedef struct { int64_t first; int second; } pa_pair;

static inline pa_pair pa_range_next(pa_range *it) {
    pa_pair out;
    out.second = it->step > 0 ? it->start < it->stop : it->start > it->stop;
    out.first = it->start;
    if (out.second) it->start += it->step;
    return out;
}
static inline int64_t pa_floordiv(int64_t a, int64_t b) {
    int64_t q = a / b;
    return (a % b != 0 && ((a < 0) != (b < 0))) ? q - 1 : q;
}
static inline int64_t pa_mod(int64_t a, int64_t b) {
    int64_t r = a % b;
    return (r != 0 && ((r < 0) != (b < 0))) ? r + b : r;
}
static inline double pa_fmod(double a, double b) {
    double r = fmod(a, b);
    return (r != 0.0 && ((r < 0.0) != (b < 0.0))) ? r + b : r;
}
static inline int64_t pa_ipow(int64_t a, int64_t n) {
    int64_t r = 1;
    while (n-- > 0) r *= a;
    return r;
}
static inline double pa_sign(double x) { return (x > 0.0) - (x < 0.0); }
static inline int64_t pa_index(int64_t i, int64_t n) { return i < 0 ? i + n : i; }

/* a slice a:b:c (has_start, has_stop: not None) and where it falls in n items (Python's
   rules: negative bounds count from the end, bounds clipped; a step of 0 is refused by
   numba before it gets here) */
typedef struct { int64_t start, stop, step; int has_start, has_stop; } pa_slice;
typedef struct { int64_t start, length; } pa_span;
static inline int64_t pa_clip(int64_t i, int64_t n, int64_t lo, int64_t hi) {
    if (i < 0) i += n;
    return i < lo ? lo : (i > hi ? hi : i);
}
static inline pa_span pa_slice_span(pa_slice s, int64_t n) {
    pa_span out;
    int64_t start, stop;
    if (s.step > 0) {
        start = s.has_start ? pa_clip(s.start, n, 0, n) : 0;
        stop = s.has_stop ? pa_clip(s.stop, n, 0, n) : n;
        out.length = stop > start ? (stop - start + s.step - 1) / s.step : 0;
    } else {
        start = s.has_start ? pa_clip(s.start, n, -1, n - 1) : n - 1;
        stop = s.has_stop ? pa_clip(s.stop, n, -1, n - 1) : -1;
        out.length = start > stop ? (start - stop - s.step - 1) / (-s.step) : 0;
    }
    out.start = start;
    return out;
}
""" + ARENA_TYPES + r"""
/* the arena: arrays a function allocates (np.empty, np.zeros, np.full, .copy()) live
   until the arena is reset or freed by whoever called the entry point; a reset keeps the
   memory, so a caller that runs an entry point again allocates nothing new */
struct pa_chunk { struct pa_chunk *next; int64_t size, used; double data[]; };
static void *pa_alloc(pa_arena *m, int64_t bytes) {
    int64_t n = bytes > 0 ? (bytes + 7) / 8 : 1;
    while (m->current && m->current->size - m->current->used < n && m->current->next)
        m->current = m->current->next;
    if (!m->current || m->current->size - m->current->used < n) {
        int64_t size = n > 4096 ? n : 4096;
        pa_chunk *c = (pa_chunk *)malloc(sizeof(pa_chunk) + (size_t)size * sizeof(double));
        if (!c) { m->failed = 1; return NULL; }
        c->size = size; c->used = 0;
        c->next = m->current ? m->current->next : NULL;
        if (m->current) m->current->next = c; else m->first = c;
        m->current = c;
    }
    m->current->used += n;
    return m->current->data + (m->current->used - n);
}
void pa_arena_reset(pa_arena *m) {
    pa_chunk *c;
    for (c = m->first; c; c = c->next) c->used = 0;
    m->current = m->first;
    m->failed = 0;
}
void pa_arena_free(pa_arena *m) {
    while (m->first) { pa_chunk *next = m->first->next; free(m->first); m->first = next; }
    m->current = NULL;
}
"""



@dataclass
class CUnit:
    """The C translation of a set of kernel functions: ``source`` (one C file: types,
    then the functions, ``static`` but for the entry points) and the ``header`` that
    declares the entry points and the types they take."""

    source: str
    header: str
    entry_points: tuple[str, ...]


@dataclass
class _Function:
    name: str
    prototype: str
    body: list[str] = field(default_factory=list)
    arena: bool = False  # it (or what it calls) allocates: its first parameter is the arena


class _Translator:
    def __init__(self, shadows: _Shadows):
        self.shadows = shadows
        self.structs: dict[object, tuple[str, str]] = {}
        self.functions: dict[tuple, _Function] = {}
        self.order: list[tuple] = []
        self.entries: dict[str, str] = {}
        self.constants: list[str] = []  # global arrays frozen into the code
        self.counter = itertools.count()

    # -- types -------------------------------------------------------------------------
    def ctype(self, t) -> str | None:
        """The C type of a numba type; None for values that have no run-time form
        (functions, modules, classes, None)."""
        if isinstance(t, types.Literal):
            t = t.literal_type if hasattr(t, "literal_type") else types.unliteral(t)
        if isinstance(t, types.Boolean):
            return "int"
        if isinstance(t, types.Integer):
            return f"{t}_t"  # int64_t, uint8_t, …
        if isinstance(t, types.Float):
            return "double" if t.bitwidth == 64 else "float"
        if isinstance(t, types.Array):
            return self._array(t)
        if isinstance(t, types.BaseTuple):
            return self._tuple(t) if len(t) else None
        if isinstance(t, types.RangeType | types.RangeIteratorType):
            return "pa_range"
        if isinstance(t, types.Pair):
            return "pa_pair"
        if isinstance(t, types.SliceType):
            return "pa_slice"
        if isinstance(t, types.NoneType | types.Omitted | types.Function | types.Dispatcher
                      | types.Module | types.NumberClass | types.Dummy):
            return None
        raise CSourceError(f"the C back end has no type for {t}")

    def _array(self, t: types.Array) -> str:
        key = ("array", t.dtype, t.ndim)
        if key not in self.structs:  # numpy's bool is one byte
            element = "uint8_t" if isinstance(t.dtype, types.Boolean) else self.ctype(t.dtype)
            name = f"pa_arr_{re.sub(r'[^a-z0-9]', '', str(t.dtype))}_{t.ndim}d"
            self.structs[key] = (name, f"typedef struct {{ {element} *data; int64_t "
                                       f"shape[{t.ndim}]; int64_t strides[{t.ndim}]; }} "
                                       f"{name};")
        return self.structs[key][0]

    def _tuple(self, t: types.BaseTuple) -> str:
        key = ("tuple", t)
        if key not in self.structs:
            members = [self.ctype(e) for e in _members(t)]
            name = f"pa_tuple_{len(self.structs)}"
            body = " ".join(f"{m} f{i};" for i, m in enumerate(members) if m is not None)
            self.structs[key] = (name, f"typedef struct {{ {body or 'int empty;'} }} {name};")
        return self.structs[key][0]

    # -- functions ---------------------------------------------------------------------
    def function(self, py_func: Callable, argtypes: Sequence) -> _Function:
        """The C function of ``py_func`` typed for ``argtypes`` (translated on first need)."""
        key = (py_func, tuple(argtypes))
        if key not in self.functions:
            name = f"pa_{py_func.__name__.strip('_')}_{next(self.counter)}"
            self.functions[key] = _Function(name, "")
            _FunctionWriter(self, py_func, tuple(argtypes), self.functions[key]).write()
            self.order.append(key)
        return self.functions[key]

    def entry(self, name: str, inner: _Function) -> str:
        """An exported function ``name`` that calls the (static) ``inner``; one that
        allocates takes the arena (``pa_arena *``) first, as ``inner`` does."""
        prototype = re.sub(r"^(static|PA_INLINE) ", "", inner.prototype).replace(
            f" {inner.name}(", f" {name}(", 1)
        arguments = ", ".join(re.findall(r"[ *](pa_mem|a\d+)(?=[,)])", inner.prototype))
        call = f"{inner.name}({arguments})"
        body = call if prototype.startswith("void ") else f"return {call}"
        self.entries[name] = f"{prototype} {{ {body}; }}"
        return prototype

    def unit(self) -> CUnit:
        structs = "\n".join(definition for _, definition in self.structs.values())
        prototypes = "\n".join(self.functions[k].prototype + ";" for k in self.order)
        bodies = "\n\n".join("\n".join(self.functions[k].body) for k in self.order)
        source = "\n".join([PRELUDE, structs, "", *self.constants, "", prototypes, "", bodies,
                            "", *self.entries.values(), ""])
        header = "\n".join(["#include <stdint.h>", ARENA_TYPES, ARENA_FUNCTIONS, structs, "",
                            *(e.split(" {", 1)[0] + ";" for e in self.entries.values()), ""])
        return CUnit(source, header, tuple(self.entries))


@dataclass(frozen=True)
class _Method:
    """A method of an array (``a.copy``), bound by a getattr and called next."""

    array: ir.Var
    attr: str


def _members(t: Any) -> tuple:
    """The member types of a numba tuple type."""
    return tuple(t.types)


@register_pass(mutates_CFG=False, analysis_only=True)
class _KeepTypedIR(FunctionPass):
    """The last pass of ``_TypedIR``: its result is the typed IR (nothing is lowered)."""

    _name = "pneumact_keep_typed_ir"

    def __init__(self):
        FunctionPass.__init__(self)

    def run_pass(self, state) -> bool:
        state.cr = (state.type_annotation, signature(state.return_type, *state.args))
        return False


class _TypedIR(CompilerBase):
    """numba's pipeline up to the typed, inlined and rewritten IR, without lowering: the
    C back end needs the types, not machine code."""

    def define_pipelines(self):
        manager = PassManager("pneumact typed IR")
        manager.passes.extend(DefaultPassBuilder.define_untyped_pipeline(self.state).passes)
        manager.passes.extend(DefaultPassBuilder.define_typed_pipeline(self.state).passes)
        manager.add_pass(AnnotateTypes, "annotate types")
        manager.add_pass(_KeepTypedIR, "keep the typed IR")
        manager.finalize()
        return [manager]


def _typed_ir(py_func: Callable, argtypes: tuple):
    """numba's typed IR of ``py_func`` for ``argtypes`` (blocks, variable types, call
    signatures, the function's signature), typed afresh: a kernel's cached dispatchers
    keep no IR. A TypingError is left as it is (``_Shadows.typed_ir`` names it)."""
    target = registry.cpu_target
    flags = Flags()
    # a function may return an array it allocates (the integrator's state)
    flags.nrt = True  # type: ignore[misc, assignment]  # numba's Flags declare options so
    annotation, typed = compile_extra(target.typing_context, target.target_context, py_func,
                                      argtypes, None, flags, {}, pipeline_class=_TypedIR)
    return annotation.blocks, annotation.typemap, annotation.calltypes, typed


class _TypingOnly(registry.CPUDispatcher):
    """The stand-in of a compiled function while one ``translate`` types what it calls.

    numba types a call of a dispatcher by compiling the dispatcher for the argument
    types (``Dispatcher.get_call_template`` calls ``compile``, then offers the
    signatures of its overloads): machine code for every function a kernel calls, most
    of the time a translation takes. This subclass's ``compile`` only types the
    function (``_Shadows.typed_ir``, no lowering) and records the signature, which is
    what the call template offers; nothing is compiled and the original dispatcher is
    left as it was. Its ``py_func`` is the original's function rebound to a copy of its
    globals in which compiled functions are stand-ins too (``_Shadows.function``), so
    what it calls is typed the same way.

    An ``inline="always"`` function is not inlined into its callers' IR here (unless
    ``_Shadows.inline``): it is typed once per argument types and written as a C
    function of its own, which the C compiler inlines where it pays. numba's inlining
    copies the callee into every call site before typing, so each copy is typed again
    (one actuator's kernel: 9.1 s of typing and 540 kB of C inlined, 5.0 s and 344 kB
    not). It is declared ``PA_INLINE`` (always inlined by GCC and clang), so the
    machine code is what it was; the arithmetic is the same either way (``-std=c99``
    contracts nothing)."""

    def __init__(self, original: Any, py_func: Callable, shadows: _Shadows):
        options = dict(original.targetoptions)
        if not shadows.inline:
            options.pop("inline", None)
        super().__init__(py_func, locals=dict(original.locals), targetoptions=options)
        self.original = original
        self._shadows = shadows
        self._typed: dict[tuple, Any] = {}  # argument types -> signature
        self._typing: set[tuple] = set()

    def compile(self, sig):
        args, _ = sigutils.normalize_signature(sig)
        args = tuple(args)
        if args not in self._typed:
            if args in self._typing:
                raise CSourceError(f"{self.py_func.__qualname__} calls itself; the C back "
                                   "end does not type recursive functions")
            self._typing.add(args)
            try:
                self._typed[args] = self._shadows.typed_ir(self.py_func, args)[3]
            except numba.core.errors.ForceLiteralArg as error:  # as Dispatcher.compile does
                raise error.bind_fold_arguments(
                    lambda a, k: self.fold_argument_types(a, k)[1]) from None
            finally:
                self._typing.discard(args)
        return None

    @property
    def nopython_signatures(self):
        return list(self._typed.values())


class _Shadows:
    """The typing of one ``translate``: each compiled function's stand-in
    (``_TypingOnly``), each namespace's copy that holds the stand-ins, and each function's
    typed IR per argument types, typed once (the stand-in types a callee for its caller's
    typing; the C writer reads the same IR). With ``enabled`` False functions are typed
    in their own globals, and numba compiles what they call (the way before stand-ins:
    the tests compare the two)."""

    def __init__(self, enabled: bool = True, inline: bool = False):
        self.enabled = enabled
        self.inline = inline
        self.dispatchers: dict[int, tuple[Any, _TypingOnly]] = {}  # id -> (original, shadow)
        self.namespaces: dict[int, tuple[dict, dict]] = {}  # id -> (original, copy)
        self.functions: dict[int, tuple[Callable, Callable]] = {}  # id -> (original, rebound)
        self.typed: dict[tuple, tuple] = {}
        self.inline_always: set[int] = set()  # ids of rebound functions declared so

    def inlined(self, py_func: Callable) -> bool:
        """Whether ``py_func`` was declared ``inline="always"`` (numba inlines it; the C
        compiler is told to: ``PA_INLINE``)."""
        return id(py_func) in self.inline_always

    def typed_ir(self, py_func: Callable, argtypes: tuple) -> tuple:
        key = (py_func, argtypes)
        if key not in self.typed:
            self.typed[key] = _typed_ir(py_func, argtypes)
        return self.typed[key]

    def function(self, py_func: Callable) -> Callable:
        """``py_func`` rebound to the copy of its globals that holds stand-ins."""
        if not self.enabled or not isinstance(py_func, pytypes.FunctionType):
            return py_func
        if id(py_func) not in self.functions:
            closure = py_func.__closure__
            if closure is not None:
                closure = tuple(pytypes.CellType(self.stand_in(_contents(c)))
                                if _is_dispatcher(_contents(c)) else c for c in closure)
            namespace = self.namespace(py_func.__globals__)
            if id(py_func) in self.functions:  # rebound meanwhile: it is in that namespace
                return self.functions[id(py_func)][1]
            rebound = pytypes.FunctionType(py_func.__code__, namespace, py_func.__name__,
                                           py_func.__defaults__, closure)
            rebound.__qualname__ = py_func.__qualname__
            rebound.__module__ = py_func.__module__
            rebound.__doc__ = py_func.__doc__
            rebound.__kwdefaults__ = py_func.__kwdefaults__
            rebound.__dict__.update(py_func.__dict__)
            self.functions[id(py_func)] = (py_func, rebound)
            self.functions[id(rebound)] = (rebound, rebound)
        return self.functions[id(py_func)][1]

    def namespace(self, original: dict) -> dict:
        """The copy of a namespace in which every compiled function is its stand-in."""
        if id(original) not in self.namespaces:
            copy = dict(original)
            self.namespaces[id(original)] = (original, copy)
            for name, value in original.items():
                if _is_dispatcher(value):
                    copy[name] = self.stand_in(value)
        return self.namespaces[id(original)][1]

    def stand_in(self, dispatcher: Any) -> Any:
        if id(dispatcher) not in self.dispatchers:
            py_func = self.function(dispatcher.py_func)
            if id(dispatcher) not in self.dispatchers:  # else made meanwhile, for its module
                original = dispatcher_of(dispatcher)
                shadow = _TypingOnly(original, py_func, self)
                self.dispatchers[id(dispatcher)] = (dispatcher, shadow)
                if original.targetoptions.get("inline") == "always":
                    self.inline_always.add(id(py_func))
        return self.dispatchers[id(dispatcher)][1]


def _is_dispatcher(value: Any) -> bool:
    return is_compiled_function(value) and not isinstance(value, _TypingOnly)


def _contents(cell: Any) -> Any:
    """What a closure cell holds (None for an empty cell)."""
    try:
        return cell.cell_contents
    except ValueError:
        return None


class _FunctionWriter:
    """Writes one typed function as C (see the module docstring)."""

    def __init__(self, unit: _Translator, py_func, argtypes: tuple, out: _Function):
        self.unit = unit
        self.py_func = py_func
        self.where = f"{py_func.__module__}.{py_func.__qualname__}"
        try:
            typed = unit.shadows.typed_ir(py_func, argtypes)
        except numba.core.errors.TypingError as error:
            raise CSourceError(f"{py_func.__qualname__}{argtypes}: {error}") from error
        self.blocks, self.typemap, self.calltypes, self.signature = typed
        self.out = out
        self.names: dict[str, str] = {}
        self.objects: dict[str, object] = {}  # variables bound to a function or module

    def fail(self, what: str) -> CSourceError:
        return CSourceError(f"{self.where}: the C back end does not translate {what}")

    def var(self, v: ir.Var | str) -> str:
        name = v if isinstance(v, str) else v.name
        if name not in self.names:
            self.names[name] = f"v{len(self.names)}_{re.sub(r'[^A-Za-z0-9]', '_', name)[-24:]}"
        return self.names[name]

    def type_of(self, v: ir.Var):
        return self.typemap[v.name]

    def write(self) -> None:
        for block in self.blocks.values():
            for stmt in block.body:
                if isinstance(stmt, ir.StaticRaise | ir.Raise | ir.DynamicRaise):
                    raise self.fail(f"a raise statement (line {stmt.loc.line}); a kernel "
                                    "function must not raise")
        try:
            self._write()
        except CSourceError as error:
            if str(error).startswith(self.where):
                raise
            raise CSourceError(f"{self.where}: {error}") from error

    def _write(self) -> None:
        rtype = self.unit.ctype(self.signature.return_type) or "void"
        params = [f"{self.unit.ctype(t)} a{i}" for i, t in enumerate(self.signature.args)
                  if self.unit.ctype(t) is not None]
        lines: list[str] = []
        for label in sorted(self.blocks):
            lines.append(f"  L{label}:;")
            for stmt in self.blocks[label].body:
                lines.extend("    " + s for s in self.statement(stmt, rtype))
        if self.out.arena:  # known once the body is written
            params.insert(0, "pa_arena *pa_mem")
        storage = "PA_INLINE" if self.unit.shadows.inlined(self.py_func) else "static"
        self.out.prototype = f"{storage} {rtype} {self.out.name}({', '.join(params) or 'void'})"
        declarations = []
        for name, cname in self.names.items():
            ctype = self.unit.ctype(self.typemap[name]) if name in self.typemap else None
            if ctype is not None:
                declarations.append(f"    {ctype} {cname};")
        first = min(self.blocks)
        self.out.body = [self.out.prototype + " {", *declarations, f"    goto L{first};",
                         *lines, "}"]

    # -- statements --------------------------------------------------------------------
    def statement(self, stmt, rtype: str) -> list[str]:
        if isinstance(stmt, ir.Assign):
            return self.assign(stmt.target, stmt.value)
        if isinstance(stmt, ir.Del):
            return []
        if isinstance(stmt, ir.Jump):
            return [f"goto L{stmt.target};"]
        if isinstance(stmt, ir.Branch):
            return [f"if ({self.var(stmt.cond)}) goto L{stmt.truebr}; else goto L{stmt.falsebr};"]
        if isinstance(stmt, ir.Return):
            if rtype == "void":
                return ["return;"]
            return [f"return {self.var(stmt.value)};"]
        if isinstance(stmt, ir.SetItem):
            return [f"{self.element(stmt.target, stmt.index)} = {self.var(stmt.value)};"]
        if isinstance(stmt, ir.StaticSetItem):
            return [f"{self.element(stmt.target, stmt.index_var)} = {self.var(stmt.value)};"]
        raise self.fail(f"the statement {stmt!r}")

    def assign(self, target: ir.Var, value) -> list[str]:
        t = self.type_of(target)
        if isinstance(value, ir.Global | ir.FreeVar):
            return self.constant(target, value.value)
        if isinstance(value, ir.Const):
            return self.constant(target, value.value)
        if self.unit.ctype(t) is None:  # a function, module or None: remember what it is
            if isinstance(value, ir.Var) and value.name in self.objects:
                self.objects[target.name] = self.objects[value.name]
            elif isinstance(value, ir.Expr) and value.op == "getattr":
                base = self.objects.get(value.value.name)
                if base is not None:
                    self.objects[target.name] = getattr(base, value.attr)
                elif isinstance(self.type_of(value.value), types.Array):
                    self.objects[target.name] = _Method(value.value, value.attr)
            elif isinstance(value, ir.Expr) and value.op == "call":
                return [self.call(target, value) + ";"]
            return []
        lhs = self.var(target)
        if isinstance(value, ir.Arg):
            return [f"{lhs} = a{value.index};"]
        if isinstance(value, ir.Var):
            return [f"{lhs} = {self.coerce(value, t)};"]
        if isinstance(value, ir.Expr) and value.op == "call":
            allocation = self.allocation(target, value)
            if allocation is not None:
                return allocation
        if isinstance(value, ir.Expr):
            return [f"{lhs} = {self.expression(target, value)};"]
        raise self.fail(f"the assignment {target} = {value!r}")

    def allocation(self, target: ir.Var, expr: ir.Expr) -> list[str] | None:
        """A new array (np.empty, np.zeros, np.full, a.copy()) in the arena, as
        statements; None for any other call."""
        fn = self.objects.get(expr.func.name)
        method = fn if isinstance(fn, _Method) else None
        copy = method is not None and method.attr == "copy" and not expr.args
        numpy_new = (getattr(fn, "__name__", None) in ALLOCATORS
                     and getattr(fn, "__module__", None) == "numpy")
        if not (copy or numpy_new):
            return None
        t = self.type_of(target)
        if not isinstance(t, types.Array) or t.layout != "C":
            raise self.fail(f"an allocation of {t}")
        if expr.vararg or any(name != "dtype" for name, _ in expr.kws):
            raise self.fail(f"the arguments of {fn!r} but the shape, fill value and dtype")
        lhs, ndim = self.var(target), t.ndim
        element = "uint8_t" if isinstance(t.dtype, types.Boolean) else self.unit.ctype(t.dtype)
        if method is not None:
            source = self.var(method.array)
            shape = [f"{source}.shape[{k}]" for k in range(ndim)]
        else:
            size = self.type_of(expr.args[0])
            if isinstance(size, types.BaseTuple):
                shape = [f"{self.var(expr.args[0])}.f{k}" for k in range(len(size))]
            else:
                shape = [self.var(expr.args[0])]
            if len(shape) != ndim:
                raise self.fail(f"an allocation of {t} with the shape {size}")
        out = [f"{lhs}.shape[{k}] = {shape[k]};" for k in range(ndim)]
        out.append(f"{lhs}.strides[{ndim - 1}] = 1;")
        for k in range(ndim - 2, -1, -1):
            out.append(f"{lhs}.strides[{k}] = {lhs}.strides[{k + 1}] * {lhs}.shape[{k + 1}];")
        count = " * ".join(f"{lhs}.shape[{k}]" for k in range(ndim))
        out.append(f"{lhs}.data = ({element} *)pa_alloc(pa_mem, ({count}) * "
                   f"(int64_t)sizeof({element}));")
        self.out.arena = True
        name = getattr(fn, "__name__", "")
        if copy or name != "empty":
            index = f"pa_i{next(self.unit.counter)}"
            if copy:
                value = f"{source}.data[{self._unravel(index, source, ndim)}]"
            elif name == "zeros":
                value = "0"
            else:
                value = self.var(expr.args[1])
            out.append(f"for (int64_t {index} = 0; {index} < {count}; {index}++) "
                       f"{lhs}.data[{index}] = {value};")
        return out

    @staticmethod
    def _unravel(flat: str, array: str, ndim: int) -> str:
        """The strided offset in ``array`` of the row-major flat index ``flat``."""
        terms, rest = [], flat
        for k in range(ndim - 1, -1, -1):
            terms.append(f"(({rest}) % {array}.shape[{k}]) * {array}.strides[{k}]")
            rest = f"({rest}) / {array}.shape[{k}]"
        return " + ".join(terms)

    def constant(self, target: ir.Var, value) -> list[str]:
        t = self.type_of(target)
        ctype = self.unit.ctype(t)
        if ctype is None:
            self.objects[target.name] = value
            return []
        if isinstance(value, np.ndarray) and isinstance(t, types.Array):
            return [f"{self.var(target)} = {self.constant_array(value, t)};"]
        return [f"{self.var(target)} = {self.literal(value, t)};"]

    def constant_array(self, value: np.ndarray, t: types.Array) -> str:
        """A global array (frozen into the compiled code as a constant): its elements as
        a static C array, the struct onto them."""
        if not isinstance(t.dtype, types.Float | types.Integer) or value.ndim != t.ndim:
            raise self.fail(f"the global array of {t}")
        element = self.unit.ctype(t.dtype)
        name = f"pa_const_{next(self.unit.counter)}"
        flat = np.ascontiguousarray(value).ravel()
        items = ", ".join(self.literal(v, t.dtype) for v in flat.tolist()) or "0"
        self.unit.constants.append(f"static const {element} {name}[] = {{{items}}};")
        shape = ", ".join(str(n) for n in value.shape) or "0"
        strides = [1] * value.ndim
        for k in range(value.ndim - 2, -1, -1):
            strides[k] = strides[k + 1] * value.shape[k + 1]
        return (f"(({self.unit.ctype(t)}){{({element} *){name}, {{{shape}}}, "
                f"{{{', '.join(map(str, strides))}}}}})")

    def literal(self, value, t) -> str:
        if isinstance(t, types.Literal):
            t = types.unliteral(t)
        if isinstance(value, bool | np.bool_):
            return "1" if value else "0"
        if isinstance(value, int | np.integer):
            return f"INT64_C({int(value)})" if isinstance(t, types.Integer) else repr(float(value))
        if isinstance(value, float | np.floating):
            value = float(value)
            if math.isnan(value):
                return "NAN"
            if math.isinf(value):
                return "INFINITY" if value > 0 else "(-INFINITY)"
            return repr(value)
        if isinstance(value, tuple) and isinstance(t, types.BaseTuple):
            items = ", ".join(self.literal(v, e) for v, e in zip(value, _members(t), strict=True)
                              if self.unit.ctype(e) is not None)
            return f"(({self.unit.ctype(t)}){{{items}}})"
        raise self.fail(f"the constant {value!r} of type {t}")

    def coerce(self, v: ir.Var, to) -> str:
        """``v`` as a value of type ``to``: tuples of other member types (a literal
        member, an int where a float goes) are rebuilt member by member."""
        have = self.type_of(v)
        if not (isinstance(to, types.BaseTuple) and isinstance(have, types.BaseTuple)):
            return self.var(v)
        return self._member(self.var(v), have, to)

    def _member(self, expr: str, have, to) -> str:
        if isinstance(to, types.BaseTuple) and isinstance(have, types.BaseTuple):
            if self.unit.ctype(to) == self.unit.ctype(have):
                return expr
            items = [self._member(f"{expr}.f{i}", h, t)
                     for i, (h, t) in enumerate(zip(_members(have), _members(to), strict=True))
                     if self.unit.ctype(t) is not None]
            return f"(({self.unit.ctype(to)}){{{', '.join(items)}}})"
        return f"(({self.unit.ctype(to)}){expr})"

    # -- expressions -------------------------------------------------------------------
    def expression(self, target: ir.Var, expr: ir.Expr) -> str:
        op = expr.op
        if op in ("binop", "inplace_binop"):
            fn = expr.fn if op == "binop" else expr.immutable_fn
            return self.binary(fn, expr.lhs, expr.rhs, self.type_of(target))
        if op == "unary":
            fn = expr.fn if callable(expr.fn) else {"-": operator.neg, "+": operator.pos,
                                                     "not": operator.not_}[expr.fn]
            return f"({UNARY[fn]}{self.var(expr.value)})"
        if op == "call":
            return self.call(target, expr)
        if op in ("getitem", "typed_getitem"):
            return self.item(expr.value, expr.index)
        if op == "static_getitem":
            return self.item(expr.value, expr.index_var, static=expr.index)
        if op == "build_tuple":
            t = self.type_of(target)
            items = [self.var(v) for v, e in zip(expr.items, _members(t), strict=True)
                     if self.unit.ctype(e) is not None]
            return f"(({self.unit.ctype(t)}){{{', '.join(items)}}})"
        if op in ("exhaust_iter", "cast"):
            return self.coerce(expr.value, self.type_of(target))
        if op == "getiter":
            return self.var(expr.value)
        if op == "iternext":
            return f"pa_range_next(&{self.var(expr.value)})"
        if op == "pair_first":
            return f"{self.var(expr.value)}.first"
        if op == "pair_second":
            return f"{self.var(expr.value)}.second"
        if op == "getattr":
            return self.attribute(target, expr)
        if op == "null":  # a placeholder numba assigns before a variable's real value
            return f"(({self.unit.ctype(self.type_of(target))}){{0}})"
        raise self.fail(f"the expression {expr!r}")

    def binary(self, fn, lhs: ir.Var, rhs: ir.Var, result) -> str:
        a, b = self.var(lhs), self.var(rhs)
        ta, tb = types.unliteral(self.type_of(lhs)), types.unliteral(self.type_of(rhs))
        ints = isinstance(ta, types.Integer) and isinstance(tb, types.Integer)
        if fn in (operator.truediv, operator.itruediv):
            return f"((double){a} / (double){b})"
        if fn in (operator.floordiv, operator.ifloordiv):
            return f"pa_floordiv({a}, {b})" if ints else f"floor({a} / {b})"
        if fn in (operator.mod, operator.imod):
            return f"pa_mod({a}, {b})" if ints else f"pa_fmod({a}, {b})"
        if fn in (operator.pow, operator.ipow):
            return f"pa_ipow({a}, {b})" if ints else f"pow({a}, {b})"
        if fn in (operator.is_, operator.is_not):
            # decided by the types: None is None, and a value of another type is not None
            if isinstance(ta, types.NoneType | types.Omitted) or isinstance(
                    tb, types.NoneType | types.Omitted):
                same = isinstance(ta, types.NoneType | types.Omitted) and isinstance(
                    tb, types.NoneType | types.Omitted)
                if isinstance(ta, types.Optional) or isinstance(tb, types.Optional):
                    raise self.fail("'is' comparisons of optional values")
                return "1" if same == (fn is operator.is_) else "0"
            raise self.fail("'is' comparisons")
        if fn in BINARY:
            return f"({a} {BINARY[fn]} {b})"
        raise self.fail(f"the operator {fn}")

    def attribute(self, target: ir.Var, expr: ir.Expr) -> str:
        base_type = self.type_of(expr.value)
        if isinstance(base_type, types.Array):
            arr = self.var(expr.value)
            if expr.attr == "shape":
                items = ", ".join(f"{arr}.shape[{k}]" for k in range(base_type.ndim))
                return f"(({self.unit.ctype(self.type_of(target))}){{{items}}})"
            if expr.attr == "size":
                return " * ".join(f"{arr}.shape[{k}]" for k in range(base_type.ndim))
            if expr.attr == "ndim":
                return str(base_type.ndim)
        fields = getattr(base_type, "fields", ()) if isinstance(base_type, types.BaseNamedTuple) \
            else ()
        if expr.attr in fields:  # a namedtuple's member
            return f"{self.var(expr.value)}.f{fields.index(expr.attr)}"
        base = self.objects.get(expr.value.name)
        if base is not None and isinstance(getattr(base, expr.attr, None), int | float):
            return self.literal(getattr(base, expr.attr), self.type_of(target))
        raise self.fail(f"the attribute .{expr.attr} of {base_type}")

    def item(self, value: ir.Var, index: ir.Var, static=None) -> str:
        t = self.type_of(value)
        if isinstance(t, types.BaseTuple):
            if static is None:
                kinds = {types.unliteral(e) for e in _members(t)}
                element = self.unit.ctype(kinds.pop()) if len(kinds) == 1 else None
                if element is None or len(t) == 0:
                    raise self.fail(f"the tuple {t} indexed by a run-time value")
                items = ", ".join(f"{self.var(value)}.f{k}" for k in range(len(t)))
                return (f"(({element}[]){{{items}}})"
                        f"[pa_index({self.var(index)}, {len(t)})]")
            k = static if static >= 0 else len(t) + static
            kept = [i for i, e in enumerate(_members(t)) if self.unit.ctype(e) is not None]
            return f"{self.var(value)}.f{k}" if k in kept else "0"
        if isinstance(t, types.Array):
            it = self.type_of(index)
            if isinstance(it, types.SliceType):
                return self.slice_view(value, index)
            count = len(it) if isinstance(it, types.BaseTuple) else 1
            if count < t.ndim:
                return self.view(value, index, count)
            return self.element(value, index)
        raise self.fail(f"indexing a {t}")

    def view(self, array: ir.Var, index: ir.Var, count: int) -> str:
        """``array[i]`` (or ``array[i, j]``) of an array of more dimensions: the view
        onto the rest, sharing the data."""
        t = self.type_of(array)
        arr = self.var(array)
        offset = self._offset(array, index)
        kept = range(count, t.ndim)
        view = self.unit._array(types.Array(t.dtype, t.ndim - count, "A"))
        shape = ", ".join(f"{arr}.shape[{k}]" for k in kept)
        strides = ", ".join(f"{arr}.strides[{k}]" for k in kept)
        return f"(({view}){{{arr}.data + {offset}, {{{shape}}}, {{{strides}}}}})"

    def slice_view(self, array: ir.Var, index: ir.Var) -> str:
        """``array[a:b:c]`` of a 1-d array: the view onto those items, sharing the data."""
        t = self.type_of(array)
        if t.ndim != 1:
            raise self.fail(f"slicing a {t.ndim}-d array")
        arr, span = self.var(array), f"pa_slice_span({self.var(index)}, {self.var(array)}.shape[0])"
        view = self.unit._array(types.Array(t.dtype, 1, "A"))
        return (f"(({view}){{{arr}.data + {span}.start * {arr}.strides[0], {{{span}.length}}, "
                f"{{{arr}.strides[0] * {self.var(index)}.step}}}})")

    def slice(self, args: Sequence[ir.Var]) -> str:
        """``slice(a, b[, c])`` (what ``x[a:b:c]`` calls), None bounds flagged."""
        bounds = []
        for k in range(3):
            a = args[k] if k < len(args) else None
            if a is None or isinstance(self.type_of(a), types.NoneType | types.Omitted):
                bounds.append(("1" if k == 2 else "0", "0"))
            elif isinstance(self.type_of(a), types.Optional):
                raise self.fail("a slice bound that may be None")
            else:
                bounds.append((self.var(a), "1"))
        if len(args) == 1:  # slice(b): a stop alone
            bounds = [("0", "0"), bounds[0], ("1", "0")]
        (start, has_start), (stop, has_stop), (step, _) = bounds
        return f"((pa_slice){{{start}, {stop}, {step}, {has_start}, {has_stop}}})"

    def element(self, array: ir.Var, index: ir.Var) -> str:
        t = self.type_of(array)
        if not isinstance(t, types.Array):
            raise self.fail(f"item assignment into a {t}")
        return f"{self.var(array)}.data[{self._offset(array, index)}]"

    def _offset(self, array: ir.Var, index: ir.Var) -> str:
        arr = self.var(array)
        it = self.type_of(index)
        if isinstance(it, types.BaseTuple):
            if any(not isinstance(types.unliteral(e), types.Integer) for e in _members(it)):
                raise self.fail(f"the array index {it} (slices)")
            parts = [f"pa_index({self.var(index)}.f{k}, {arr}.shape[{k}]) * {arr}.strides[{k}]"
                     for k in range(len(it))]
        elif isinstance(types.unliteral(it), types.Integer):
            parts = [f"pa_index({self.var(index)}, {arr}.shape[0]) * {arr}.strides[0]"]
        else:
            raise self.fail(f"the array index {it} (slices)")
        return " + ".join(parts)

    def call(self, target: ir.Var, expr: ir.Expr) -> str:
        fn = self.objects.get(expr.func.name)
        if expr.kws or expr.vararg:
            raise self.fail(f"keyword or star arguments in a call of {fn}")
        signature = self.calltypes[expr]
        if is_compiled_function(fn):
            args = [self.coerce(a, t) for a, t in zip(expr.args, signature.args, strict=True)
                    if self.unit.ctype(t) is not None]
            # a stand-in's function is typed already; a dispatcher that is no stand-in (one
            # reached otherwise than as a global) was compiled by numba: its function is
            # rebound, so that it is one C function with what reaches it as a stand-in
            callee = self.unit.function(self.unit.shadows.function(fn.py_func), signature.args)
            if callee.arena:
                self.out.arena = True
                args.insert(0, "pa_mem")
            return f"{callee.name}({', '.join(args)})"
        args = [self.var(a) for a in expr.args if self.unit.ctype(self.type_of(a)) is not None]
        if fn in (builtins.abs, np.abs, np.absolute):
            t = types.unliteral(self.type_of(expr.args[0]))
            return f"{'llabs' if isinstance(t, types.Integer) else 'fabs'}({args[0]})"
        if fn in (builtins.min, builtins.max) and len(args) >= 2 and all(
                isinstance(types.unliteral(self.type_of(a)), types.Number) for a in expr.args):
            compare = "<" if fn is builtins.min else ">"
            result = args[0]  # Python's: the first of equal values, left to right
            for b in args[1:]:
                result = f"({b} {compare} {result} ? {b} : {result})"
            return result
        if isinstance(fn, type) and issubclass(fn, tuple) and hasattr(fn, "_fields"):
            t = self.type_of(target)  # a namedtuple built: its struct, member by member
            items = [self._member(self.var(a), self.type_of(a), m)
                     for a, m in zip(expr.args, _members(t), strict=True)
                     if self.unit.ctype(m) is not None]
            return f"(({self.unit.ctype(t)}){{{', '.join(items)}}})"
        if fn is builtins.round and len(args) == 1:  # numba: llvm.rint (half to even), to int
            if isinstance(types.unliteral(self.type_of(expr.args[0])), types.Integer):
                return args[0]
            return f"(({self.unit.ctype(types.unliteral(self.type_of(target)))})rint({args[0]}))"
        if fn is builtins.int:
            return f"((int64_t)({args[0]}))"
        if fn is builtins.float:
            return f"((double)({args[0]}))"
        if isinstance(fn, type) and issubclass(fn, np.integer | np.floating) and len(args) == 1:
            return f"(({self.unit.ctype(types.unliteral(self.type_of(target)))})({args[0]}))"
        if fn is builtins.bool:
            return f"(({args[0]}) != 0)"
        if fn is builtins.slice:
            return self.slice(expr.args)
        if fn is builtins.range:
            start, stop, step = ({1: ["0", args[0], "1"], 2: [*args, "1"], 3: args}[len(args)])
            return f"((pa_range){{{start}, {stop}, {step}}})"
        if fn is builtins.len:
            return f"{self.var(expr.args[0])}.shape[0]"
        if fn is np.sign:
            return f"pa_sign({args[0]})"
        name = str(getattr(fn, "__name__", ""))
        if name in MATH and getattr(fn, "__module__", None) in ("math", "numpy", None):
            return f"{MATH[name]}({', '.join(args)})"
        raise self.fail(f"a call of {fn!r}")


#: the typing of the last few translations shared by name (``translate``'s ``share``)
_SHARED: OrderedDict[str, _Shadows] = OrderedDict()
#: how many shared typings are kept (one kernel's: ~8 MB)
SHARED_KEPT = 4
_SHARED_LOCK = threading.RLock()


def translate(roots: dict[str, tuple[Callable, Sequence]], share: str | None = None
              ) -> CUnit:
    """C source of the functions ``roots`` (entry name -> (a compiled kernel function
    or its Python function, numba argument types)) and of everything they call. The
    functions are typed, not compiled: numba compiles none of them for this.

    ``share``: a name under which the typing is kept for the next translations that
    give it (one kernel's libraries, run, sensitivities, states, and its FMU, call the
    same functions: typed once, a later group's translation costs a half to a third);
    the last ``SHARED_KEPT`` names are kept, and translations sharing one run one at a
    time."""
    if share is None:
        return _translate(roots, _Shadows())
    with _SHARED_LOCK:
        shadows = _SHARED.pop(share, None) or _Shadows()
        _SHARED[share] = shadows
        while len(_SHARED) > SHARED_KEPT:
            _SHARED.popitem(last=False)
        return _translate(roots, shadows)


def _translate(roots: dict[str, tuple[Callable, Sequence]], shadows: _Shadows) -> CUnit:
    unit = _Translator(shadows)
    for entry, (function, argtypes) in roots.items():
        py_func = shadows.function(getattr(function, "py_func", function))
        unit.entry(entry, unit.function(py_func, argtypes))
    return unit.unit()
