"""The kernel core, the bottom layer of the compiled code: what a template or a
component needs to declare compiled functions and be joined into a kernel, and nothing
of any model.

- ``marks``: the ``kernel`` mark of a template's functions;
- ``component``: ``Block`` (a component's parameters), ``StateSpec``, ``Part``;
- ``channels``: the input channels, declared by name;
- ``assembly``: a model's components joined (layout of parameters, states, outputs);
- ``codegen``: the generated kernel module per component combination;
- ``signals``: the input signals and their compiled evaluation;
- ``features``: the hysteresis features, compiled once per machine (not per kernel):
  the batch engine computes them for every row (``pneumact.analysis`` is their public
  face);
- ``integrators`` (with ``linalg``): RODAS4 and Dormand-Prince 5(4), one driver, with
  forward sensitivities;
- ``units``: the SI unit of each signal name.

A model's own template (its right-hand side and Jacobian) lies beside the model in
``pneumact.models``.
"""

from .marks import kernel

__all__ = ["kernel"]
