"""Protocols shared by several specifications: the rate-gyro programme a specification plans
(:mod:`gonio.protocol.programme`: ``Segment``, ``Programme``) and the rate protocol both rate
specifications read (:mod:`gonio.protocol.rate`). This layer sits below the bench and the
instruments, which both run a programme; it imports only physics and formats. A
specification's own protocol lives in its package (the optical draft's rounds and series).
"""
