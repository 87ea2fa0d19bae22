"""What an ECU's diagnosis says, step by step (`DiagRecord`: the content of an FDI_Diagnosis frame), and the
structural facts of the table it runs (`TableClasses`): what sessions record and the monitor scores."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from fdi_host.sim.faults import FAULT_IDS


@dataclass(frozen=True)
class DiagRecord:
    """One diagnosis step: its time on the drive's clock [s] and the content of the FDI_Diagnosis frame."""

    t: float
    alarm_mask: int
    candidates: int
    iso_class: int = 0
    status: int = 0


def isolates_fault(candidates: int, fault_class: int, fault_bit: int) -> bool:
    """True when a diagnosis' candidate faults isolate a fault to its structural isolability class: they hold the
    fault and lie within its class. That is the diagnosis library's `isolated` (fdi_iso.h: one class among the
    candidates) with the fault's class as `class_mask`, and the fault itself not exonerated: with measured sizes
    a quiet test may clear one fault of a class and not another, so the candidates may be part of the class
    ({f6} of {f6, f18}: the diagnosis names the fault more narrowly than the structure alone can), but never a
    part without the fault ({f18} for f6 names the right class and the wrong fault)."""
    return candidates & fault_bit != 0 and candidates & ~fault_class == 0


@dataclass(frozen=True)
class TableClasses:
    """Structural facts of a diagnosis table, per fault j (bit j = fault faults[j])."""

    signature: tuple[int, ...]  # tests sensitive to fault j (test bitmask); 0 = not detectable
    iso_class: tuple[int, ...]  # faults with the same signature as fault j (fault bitmask)
    test_names: tuple[str, ...] = ()
    faults: tuple[str, ...] = FAULT_IDS  # the table's fault names by bit (default: the vehicle simulator's)

    @staticmethod
    def from_signatures(signature: Sequence[int], test_names: Sequence[str] = (),
                        faults: Sequence[str] = FAULT_IDS) -> TableClasses:
        """Classes from the signatures: faults with equal (non-zero) signatures are not isolable."""
        sig = tuple(int(s) for s in signature)
        classes = []
        for s in sig:
            mask = 0
            if s != 0:
                for k, other in enumerate(sig):
                    if other == s:
                        mask |= 1 << k
            classes.append(mask)
        return TableClasses(sig, tuple(classes), tuple(test_names), tuple(faults))

    def bit(self, fault: str) -> int:
        """The fault's bit in the table's fault masks (ValueError for a fault the table does not name)."""
        return 1 << self.faults.index(fault)

    def detectable(self, fault: str) -> bool:
        """Whether a test of the table is sensitive to `fault` (False for a fault the table does not name: a drive
        may inject faults of a larger model than the table's)."""
        j = self.faults.index(fault) if fault in self.faults else len(self.signature)
        return j < len(self.signature) and self.signature[j] != 0

    def class_of(self, fault: str) -> int:
        """The faults not isolable from `fault` (bitmask); 0 for a fault the table does not name."""
        j = self.faults.index(fault) if fault in self.faults else len(self.iso_class)
        return self.iso_class[j] if j < len(self.iso_class) else 0

    def fault_names(self, mask: int) -> str:
        """``0b1010`` -> ``"f2,f4"`` (the table's names); ``"-"`` for an empty set."""
        return ",".join(f for j, f in enumerate(self.faults) if mask >> j & 1) or "-"

    def test_name(self, i: int) -> str:
        return self.test_names[i] if i < len(self.test_names) else f"t{i}"
