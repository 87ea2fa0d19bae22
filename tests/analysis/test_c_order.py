"""fdi_analysis.export.c_order: each `const float` definition of a generated step just before its first use, within
its own block, operands first; nothing else moves, nothing is lost (the generated C's values are checked against
Python by test_residual_c_vs_python.py and its committed copies by test_export_c.py)."""

from __future__ import annotations

import pytest

from fdi_analysis.export.c_order import defined_before_use


def body(*lines: str) -> str:
    return "\n".join(lines)


def test_a_definition_moves_to_just_before_its_first_use_with_its_operands_first() -> None:
    src = body("    const float t1 = (2.0f * b[0].x1);",
               "    const float t2 = (t1 * t1);",
               "    const float t3 = (3.0f * b[1].x1);",
               "    io->r[0] = t3;",
               "    io->r[1] = t2; /* t3 in a comment reads nothing */")
    assert defined_before_use(src).split("\n") == [
        "    const float t3 = (3.0f * b[1].x1);",
        "    io->r[0] = t3;",
        "    const float t1 = (2.0f * b[0].x1);",
        "    const float t2 = (t1 * t1);",
        "    io->r[1] = t2; /* t3 in a comment reads nothing */"]


def test_definitions_stay_in_their_block_and_out_of_nested_blocks_and_conditions() -> None:
    src = body("    const float t1 = (2.0f * in->value[3]);",
               "    const float t2 = sinf(t1);",
               "    float xh = 0.0f; /* t2 */",
               "    if ((run & 0x1U) != 0U) /* slot 0 */",
               "    {",
               "        const float t4 = (t1 + 1.0f);",
               "        const float t5 = (t4 * 2.0f);",
               "        xh = t5;",
               "    }",
               "#if FDI_GEN_SENSITIVITIES",
               "    {",
               "        sv[0] = t2;",
               "    }",
               "#endif",
               "    io->r[0] = xh;")
    out = defined_before_use(src).split("\n")
    # t1 is read first inside the slot's block: it comes just before the block's header, not into it; t2 first
    # inside the #if region: before the #if line; the slot's own definitions move inside their block
    assert out == [
        "    float xh = 0.0f; /* t2 */",
        "    const float t1 = (2.0f * in->value[3]);",
        "    if ((run & 0x1U) != 0U) /* slot 0 */",
        "    {",
        "        const float t4 = (t1 + 1.0f);",
        "        const float t5 = (t4 * 2.0f);",
        "        xh = t5;",
        "    }",
        "    const float t2 = sinf(t1);",
        "#if FDI_GEN_SENSITIVITIES",
        "    {",
        "        sv[0] = t2;",
        "    }",
        "#endif",
        "    io->r[0] = xh;"]
    assert sorted(out) == sorted(src.split("\n"))


def test_what_reads_other_memory_and_what_nothing_reads_keep_their_order() -> None:
    src = body("    const float xs = o->xh; /* the observer's state, written by the store below */",
               "    const float t9 = (4.0f * b[2].x2);",
               "    const float t8 = (5.0f * b[2].x2);",
               "    fdi_gen_obs_store(o, 1.0f, 2.0f);",
               "    io->r[0] = xs;")
    out = defined_before_use(src).split("\n")
    assert out[0].startswith("    const float xs = o->xh;")  # not moved past the store
    assert out[1:3] == ["    fdi_gen_obs_store(o, 1.0f, 2.0f);", "    io->r[0] = xs;"]
    assert out[3:] == ["    const float t9 = (4.0f * b[2].x2);", "    const float t8 = (5.0f * b[2].x2);"]


def test_an_unclosed_block_is_an_error() -> None:
    with pytest.raises(ValueError, match="not closed"):
        defined_before_use(body("    if ((run & 0x1U) != 0U)", "    {", "        io->r[0] = 1.0f;"))


def test_a_definition_never_moves_past_an_assignment_of_what_it_reads() -> None:
    src = body("    float xh = xp;",
               "    const float t1 = (2.0f * xh); /* xh before the prediction */",
               "    const float t2 = (3.0f * xp);",
               "    if ((io->restart & 0x1U) == 0U)",
               "    {",
               "        xh = fdi_gen_obs_predict(o, io->par, t2, 1.0f);",
               "    }",
               "    const float t3 = (t1 + xh);",
               "    io->r[0] = t3;")
    out = defined_before_use(src).split("\n")
    # t1 reads xh, which the block assigns: it stays before the block; t2 moves to just before it, t3 after
    assert out == [
        "    float xh = xp;",
        "    const float t1 = (2.0f * xh); /* xh before the prediction */",
        "    const float t2 = (3.0f * xp);",
        "    if ((io->restart & 0x1U) == 0U)",
        "    {",
        "        xh = fdi_gen_obs_predict(o, io->par, t2, 1.0f);",
        "    }",
        "    const float t3 = (t1 + xh);",
        "    io->r[0] = t3;"]
