"""Identification: parameters of an actuator or a friction law from measured records.

- ``identify_paper``: the paper's staged procedure (section III.2) on bench records,
  then a joint refinement, intervals that include the input noise, and a verdict per
  parameter; ``identify_signature``: what one slow up-and-down loop tells (F0, k, Fc,
  the valve engineer's bench set, spring rate, friction band and dead band);
- ``fit``: any parameters of any model fitted to one or several records (forward
  sensitivities as the Jacobian, shared or per-record parameters, multistart, profile
  likelihood);
- ``inverse_friction``: friction laws from measured motion and force (IDIM-LS);
- ``design_campaign``: the bench tests for an actuator known roughly (a plan a
  technician can run); ``synthetic_campaign``: those tests simulated with realistic
  measurement noise (``paper_campaign``: the paper's fixed set of speeds);
  ``PaperIdentification.next_round`` (``rounds``): a second campaign designed from a
  first identification's result; ``combine_rounds`` (``combine``): two rounds'
  results combined per parameter, each value saying its round.
"""

from .campaign import (
    BenchFamily,
    BenchTest,
    CampaignPlan,
    Noise,
    design_campaign,
    paper_campaign,
    synthetic_campaign,
)
from .combine import CombinedIdentification, combine_rounds
from .estimates import Estimates, linear_least_squares
from .fit import FitResult, ProfileLikelihood, experiment_for, fit
from .inverse import InverseFriction, inverse_friction
from .paper import (
    PaperIdentification,
    SignatureIdentification,
    StageResult,
    identify_paper,
    identify_signature,
    record_kind,
)

__all__ = [
    "BenchFamily",
    "BenchTest",
    "CampaignPlan",
    "CombinedIdentification",
    "Estimates",
    "FitResult",
    "InverseFriction",
    "Noise",
    "PaperIdentification",
    "ProfileLikelihood",
    "SignatureIdentification",
    "StageResult",
    "combine_rounds",
    "design_campaign",
    "experiment_for",
    "fit",
    "identify_paper",
    "identify_signature",
    "inverse_friction",
    "linear_least_squares",
    "paper_campaign",
    "record_kind",
    "synthetic_campaign",
]
