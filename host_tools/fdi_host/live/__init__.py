"""Programs on a live bus: opening a bus, sending frames at their times, the simulated vehicle on a bus
(``fdi-sim live``), the ECU process (``fdi-ecu``), the live loop runner (``fdi-live``) with restarts, and the
private network namespace the udp_multicast bus runs in."""
