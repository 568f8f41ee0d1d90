"""Pipelines: calibrate (readings or stream → results), validate (coverage on the bench), demo.

The top of the data flow: they call the stages below and write output sets; the
CLI is a thin layer over them.
"""
