"""Host-side tooling: vehicle simulator with fault injection, CAN database and logs, ECU process, monitor."""
