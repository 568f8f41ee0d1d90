"""Loaded at the start of every Python process of a ``gonio serve`` started by the records
tests with ``serve.start(..., memo=True)`` (this folder first on its PYTHONPATH): where
RECORDS_TEST_SERVER_MEMO names a folder, the pipeline and the rendering of the server's worker
processes go through the session's shared memo (tests/records/pipeline_memo.py, SessionMemo)."""

import os

if os.environ.get("RECORDS_TEST_SERVER_MEMO"):
    from tests.records.pipeline_memo import install_in_process

    install_in_process(os.environ["RECORDS_TEST_SERVER_MEMO"])
