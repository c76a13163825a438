"""The check modules of `ddgjax verify`, one per object of the reference.

Every module here is imported by `ddgjax.verify.load_checks()` and registers its checks with
`@ddgjax.verify.check`; the first line of its docstring is the section title in the report.
Checks share solved problems through small cached helpers (`_shared.py`) so that the quick run
compiles each problem structure once.
"""
