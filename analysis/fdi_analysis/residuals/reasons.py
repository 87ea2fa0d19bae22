"""Why an MSO set has no residual generator of a kind: a typed reason (an enum plus the equation and variable
it concerns) that callers match on and reports count, with a sentence for people (`Rejection.text`)."""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

from fdi_analysis.errors import FdiError


class Reason(Enum):
    """Kinds of rejection; the value is the plural phrase reports use ("2,015 contain an algebraic loop")."""

    OPEN_LOOP = "need open-loop integration"
    OBSERVER_STATES = "need open-loop integration of two or more states (one observer state per generator)"
    OBSERVER_DERIVATIVE = "differentiate a value computed from an observer state"
    NO_OBSERVER_EQUATION = "have no differential constraint to drive an observer"
    NOT_OBSERVABLE = "have an observer state the residual equation does not see"
    OBSERVER_DIVISION = "divide by a signal inside an observer"
    OBSERVER_OUTPUT = "leave only a differential constraint for the observer's residual"
    DIVISION = "divide by a signal inside a non-rational law"
    RESIDUAL_DIVISION = "have a residual equation not rational in a quotient by a signal"
    NOT_SOLVABLE = "need a non-invertible equation solved"
    UNUSABLE_EQUATION = "hold an equation the generator cannot use"
    ALGEBRAIC_LOOP = "contain an algebraic loop"
    FILTER_LEVELS = "need derivatives beyond two filter levels"
    NO_RESIDUAL = "leave no equation for a residual"
    NOT_POLYNOMIAL = "have a residual not polynomial in a quotient by a signal"
    CONSTANT_RESIDUAL = "have an identically constant residual"
    NO_REFERENCE = "need a reference drive for the observer gain"


@dataclass(frozen=True)
class Rejection:
    """One reason, with what it concerns: `equation` and `variable` (empty where not applicable) and, for
    OBSERVER_STATES, the states found."""

    kind: Reason
    text: str
    equation: str = ""
    variable: str = ""
    states: tuple[str, ...] = ()

    def __str__(self) -> str:
        return self.text


class NotRealizableError(FdiError, ValueError):
    """The MSO set has no residual generator of this kind; str() is 'not realizable: <reason>'."""

    def __init__(self, reason: Rejection) -> None:
        super().__init__(f"not realizable: {reason.text}")
        self.rejection = reason

    @property
    def reason(self) -> str:
        return self.rejection.text

    @property
    def kind(self) -> Reason:
        return self.rejection.kind
