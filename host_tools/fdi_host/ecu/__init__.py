"""The C ECU core (fw/ecu + the fw diagnoser) from Python: ctypes bindings, a session that feeds it timestamped
frames and records each step, and offline replay of frames through it."""
