"""Which part of the public API each command stands for, declared once.

The command line is a thin layer over the API, and its words are the API's: an option is
named as the parameter of the function the command calls, or the field of an object it
builds (an option object such as ``Executor``, a model part such as ``LuGre``), and its
default is that parameter's default. ``tests/unit/test_cli_meta.py`` walks every command
and checks each option against the targets named here.

Targets are "module:name" strings (a function, or a class whose fields count), so that
reading this module imports nothing heavy. ``SPELLED`` lists the few options whose word
differs from the API's, each with the parameter it stands for (a plain CSV path, a
choice that builds an object); ``OWN`` those that are the command line's own (where to
write, what to read); ``UNITS`` the options given in another unit than the API's SI.
"""

from __future__ import annotations

__all__ = ["API", "NONE_MEANS", "OWN", "SPELLED", "UNITS"]

#: the model every actuator command builds (``common.build_model``)
_MODEL = ("pneumact.models:Actuator", "pneumact.models:LuGre", "pneumact.models:GMS",
          "pneumact.models:Polytropic", "pneumact.simulation:Rodas4")
#: the default experiment of ``common.build_experiment``
_EXPERIMENT = ("pneumact.experiments:PressureCycle",)
#: what --model cylinder builds instead (``common.build_cylinder``, ``cylinder_experiment``)
_CYLINDER = ("pneumact.models:Cylinder", "pneumact.experiments:SpoolStep")
_FRICTION_TEST = ("pneumact.analysis.friction_tests:run_friction_test",)
_CONTROL = ("pneumact.control:ClosedLoop", "pneumact.control:PID", "pneumact.control:Cascade",
            "pneumact.control.study:run_loop", "pneumact.models:Actuator",
            "pneumact.models:Cylinder", "pneumact.simulation:Rodas4")

#: command (its words joined by spaces) -> the API it calls and the objects it builds
API: dict[str, tuple[str, ...]] = {
    "simulate": ("pneumact.simulation:simulate", *_MODEL, *_EXPERIMENT, *_CYLINDER),
    "simulate-batch": ("pneumact.simulation.batch:simulate_batch", *_MODEL, *_EXPERIMENT,
                       *_CYLINDER),
    "campaign": ("pneumact.identification:design_campaign",
                 "pneumact.identification:synthetic_campaign", "pneumact.identification:Noise"),
    "fit": ("pneumact.identification:fit", *_MODEL, *_CYLINDER),
    "compare": ("pneumact.validation:compare_friction_models", "pneumact.options:Executor",
                "pneumact.options:Optimizer", *_MODEL),
    "sensitivity": ("pneumact.sensitivity:sobol", "pneumact.sensitivity:src",
                    "pneumact.sensitivity:rbd_fast", "pneumact.sensitivity:model_outputs",
                    "pneumact.sensitivity:across_conditions", "pneumact.sensitivity:model_signal",
                    "pneumact.sensitivity:one_at_a_time", *_MODEL, *_EXPERIMENT, *_CYLINDER),
    "validate": ("pneumact.validation:validate", "pneumact.validation:train_test", *_MODEL),
    "reproduce": ("pneumact.reproduction:reproduce",),
    "friction-test steady-state": (*_FRICTION_TEST, "pneumact.experiments.friction:SteadyState",
                                   "pneumact.simulation:Rodas4"),
    "friction-test presliding": (*_FRICTION_TEST, "pneumact.experiments.friction:Presliding",
                                 "pneumact.simulation:Rodas4"),
    "friction-test frictional-lag": (*_FRICTION_TEST,
                                     "pneumact.experiments.friction:FrictionalLag",
                                     "pneumact.simulation:Rodas4"),
    "friction-test break-away": (*_FRICTION_TEST, "pneumact.experiments.friction:BreakAway",
                                 "pneumact.simulation:Rodas4"),
    "friction-test stick-slip": (*_FRICTION_TEST, "pneumact.experiments.friction:StickSlip",
                                 "pneumact.simulation:Rodas4"),
    "params list": ("pneumact.parameters:available_params",),
    "params show": ("pneumact.parameters:load_params",),
    "params check": ("pneumact.parameters:load_params",),
    "identify paper": ("pneumact.identification:identify_paper",),
    "identify signature": ("pneumact.identification:identify_signature",),
    "identify friction": ("pneumact.identification:inverse_friction",),
    "control step": ("pneumact.experiments:SetpointStep", *_CONTROL),
    "control profile": ("pneumact.experiments:SetpointProfile", *_CONTROL),
    "control hunting": ("pneumact.control.study:canudas_hunting", "pneumact.simulation:Rodas4"),
    "control tune": ("pneumact.control:tune", "pneumact.control:default_moves", *_CONTROL,
                     "pneumact.options:Executor"),
    "control compare": ("pneumact.control:linear_design", "pneumact.control:compare_designs",
                        *_CONTROL),
    "export fmu": ("pneumact.export:export_fmu", *_MODEL, *_CYLINDER),
}

#: options whose word is not the API's, and the parameter ("module:name.parameter") each
#: stands for
SPELLED: dict[str, str] = {
    "elements": "pneumact.models:GMS.n_elements",
    "low": "pneumact.experiments:PressureCycle.low",
    "t_end": "pneumact.experiments:PressureCycle.period",
    "signals": "pneumact.sensitivity:model_signal.signal",
    "spread": "pneumact.identification:identify_paper.prior_spread",
    "pressure_noise": "pneumact.identification:Noise.pressure",
    "position_noise": "pneumact.identification:Noise.position",
    "staged_only": "!pneumact.identification:identify_paper.refine",
    "free": "pneumact.identification:fit.free",
    "coulomb_ff": "pneumact.control:StaticCompensation.Fc",
    "observer": "pneumact.control:LuGreObserver",
    "observer_gain": "pneumact.control:LuGreObserver.gain",
    "dither": "pneumact.control:Dither",
    "load_step": "pneumact.models:Cylinder.load",
    "plant": "pneumact.control:ClosedLoop.plant",
    "column": "pneumact.experiments:SetpointProfile",
    "atol_factor": "pneumact.simulation:Rodas4.atol",
    "convergence": "pneumact.sensitivity:sobol_convergence",
    "times": "pneumact.sensitivity:model_signal.times",
    "spec": "pneumact.control:tune.specs",
    "gain_spread": "pneumact.control:tune.spread",
}

#: the command line's own options: what a command reads, where it writes, what it shows
OWN: dict[str, str] = {
    "out": "the folder a command writes its files into (atomically, all or none)",
    "input_csv": "a CSV of time and an input signal, read by experiments.from_csv (the "
                 "cylinder's: its declared inputs' columns, spool and optionally load)",
    "plan": "campaign: write the plan of the tests instead of simulating them",
    "simulate": "campaign: run a plan written by --plan (from a prior) on --params",
    "round": "campaign: which round of tests (from 2 on every test's name ends in "
             "_round<N>; design_campaign's suffix)",
    "previous": "identify paper: the folder of an earlier round's identification, combined "
                "per parameter with this one (identification.combine_rounds)",
    "partial": "identify paper: no longer needed (hidden; identified.toml is always "
               "written, the prior's values marked)",
    "validate": "identify friction: a second record to validate the estimates on",
    "version": "print the version",
    "gains_file": "control step: a gains file written by control tune (its controller)",
    "tuned": "control compare: a gains file written by control tune, run beside the "
             "linear designs",
    "format": "identify friction, compare: the reader of the record files (auto, record, "
              "emps, tudelft)",
}

#: what an API default of None stands for, by parameter name (the API builds it)
NONE_MEANS: dict[str, object] = {
    "friction": "lugre",  # LuGre()
    "chamber": "isothermal",  # Isothermal()
}

#: options given in another unit than the API's SI: API value = option value × factor
UNITS: dict[str, float] = {
    "low": 1e3,  # kPa
    "spread": 1e-2,  # %
    "sliding_speed": 1e-3,  # mm/s
    "pressure_noise": 1e3,  # kPa
    "position_noise": 1e-6,  # µm
    "resolution": 1e-6,  # µm
    "start": 1e-3,  # mm
    "stop": 1e-3,  # mm
    "at": 1e-3,  # mm
    "velocity": 1e-3,  # mm/s
}
