"""Residual generators synthesised from MSO sets (sequential residual generation).

For an MSO set of a symbolic model, `causality.synthesize` chooses a residual equation and a computation
sequence for the remaining just-determined part: algebraic steps (an equation solved for one unknown, only
where the equation is linear in it and `not_solvable_for` does not forbid it, see `solvability`; an
algebraic loop of linear equations solved jointly), derivative causality through the firmware's
state-variable filters (`signals`), and integral causality through an observer (`observer`) for one state
the sequence would otherwise integrate open loop or differentiate twice. The result
is one symbolic residual over filtered measured signals (`generator.Generator`), emitted as C (`emit_c`)
and evaluated in Python on logged or simulated signals (`evaluate`); `realizability` is the fast structural
pre-check used to keep only realizable MSO sets in the selection, `calibrate` the fault-free noise level of
each residual.
"""
