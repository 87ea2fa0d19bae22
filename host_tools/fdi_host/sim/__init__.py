"""The vehicle simulator: the dual-track plant compiled from the model file, the geometric motion controller
and its actuators, drive scenarios, Table I fault injection and sensor models. Imports only the model layer
of `fdi_analysis` (the plant is built from the model's own equations)."""
