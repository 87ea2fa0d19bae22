"""The diagnosis quality suite: every fault x scenarios x sizes x step/ramp plus fault-free driving, offline
through the C ECU core (``fdi-quality``)."""
