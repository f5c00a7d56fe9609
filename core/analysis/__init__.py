"""Analysis tools: accuracy against run time, the stability suite and exact rational arithmetic.

They import the core and are never imported by it.
"""
