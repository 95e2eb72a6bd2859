"""The kernel core, the bottom layer of the compiled code: what a template or a
component needs to declare compiled functions, and nothing of any model.

Today it holds the ``kernel`` mark, the input signals with their compiled evaluation
(``core.signals``: every model reads its inputs through it) and the hysteresis features
(``core.features``: compiled, so that the batch engine computes them in its loop;
``pneumact.analysis`` is their public face); the generator, the state and
output declarations and the integrators move here next (issue 20's plan,
``docs/architecture.md``).
"""

from .marks import kernel

__all__ = ["kernel"]
