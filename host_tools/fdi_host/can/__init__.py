"""CAN: the frame type, the DBC (the single source of every message layout and ID), E2E protection, log files,
a simulated drive's traffic and the ECU's view of it. Above the simulator, below everything that runs a bus."""
