"""A process started beside its parent (a served bench, an acquisition) that ends with it.

:func:`dies_with_parent` is a ``subprocess.Popen`` ``preexec_fn``: the child asks the kernel
for SIGTERM when the process that started it ends, however that ends (SIGKILL by a test's
timeout among the ways), so a ``gonio bench serve`` or ``gonio acquire`` started by a script
or a test is never left running alone. Linux ``prctl(PR_SET_PDEATHSIG)``; elsewhere nothing
(the starter stops its children itself on an ordinary exit). A ``preexec_fn`` runs between
``fork`` and ``exec``: the starter should have no other threads running then.
"""

from __future__ import annotations

import ctypes
import os
import signal
import sys

#: prctl(2)'s option: the signal a process gets when its parent ends
PR_SET_PDEATHSIG = 1


def dies_with_parent(sig: int = signal.SIGTERM):
    """The ``preexec_fn`` that has the child sent ``sig`` when its starter ends (called in
    the starter: it records the starter's pid)."""
    parent = os.getpid()
    prctl = None
    if sys.platform.startswith("linux"):
        try:                             # looked up here, not in the child: no dlopen there
            prctl = ctypes.CDLL(None, use_errno=True).prctl
        except (OSError, AttributeError):
            prctl = None

    def preexec() -> None:
        if prctl is None:
            return
        prctl(PR_SET_PDEATHSIG, int(sig), 0, 0, 0)
        if os.getppid() != parent:       # the starter ended before the request took
            os.kill(os.getpid(), sig)
    return preexec
