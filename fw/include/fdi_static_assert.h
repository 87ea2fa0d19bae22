/*
 * fdi_static_assert.h - compile-time assertions in C99 (no _Static_assert before C11).
 *
 * FDI_STATIC_ASSERT(cond, name) declares the array type `name` of size 1 when cond holds and of size -1
 * (a compile error naming `name`) when it does not; it generates no code and no data. `name` must be unique
 * in its scope (by convention fdi_sa_<what>). Used for the size and capacity claims of the headers and of the
 * generated vehicle code (e.g. a vehicle's signal count <= FDI_FRAME_MAX_SIGNALS). The type is never used:
 * MISRA C:2012 Rule 2.3 (advisory) is deviated at each use (fw/MISRA_DEVIATIONS.md), marked
 * `cppcheck-suppress misra-c2012-2.3` on the line before it.
 * Cost: none. Memory: none.
 */
#ifndef FDI_STATIC_ASSERT_H
#define FDI_STATIC_ASSERT_H

/* NOLINTNEXTLINE(bugprone-macro-parentheses): `name` is the declared identifier, it cannot be parenthesised */
#define FDI_STATIC_ASSERT(cond, name) typedef char name[(cond) ? 1 : -1]

#endif /* FDI_STATIC_ASSERT_H */
