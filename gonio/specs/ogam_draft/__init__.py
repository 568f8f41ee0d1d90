"""The optical-gyro angle-measuring instrument draft (JJF xxxx 光学陀螺测角仪校准规范, draft for comment).

:mod:`~gonio.specs.ogam_draft.items` the seven characteristics of clause 7;
:mod:`~gonio.specs.ogam_draft.budget` the Annex A budget. The clause-by-clause
reading is ``docs/draft-readings.md``.
"""

from gonio.specs import Specification
from gonio.specs.ogam_draft.budget import annex_a_budget
from gonio.specs.ogam_draft.items import compute_characteristics

SPEC = Specification(
    key="ogam-draft",
    title_en="Calibration Specification for Optical Gyroscope Angle Measuring Instruments "
             "(draft for comment)",
    title_zh="光学陀螺测角仪校准规范(征求意见稿)",
    clause_doc="docs/draft-readings.md",
    default_protocol="ogam-draft",
    default_bench="rlg",
    calibrate=compute_characteristics,
    budget=annex_a_budget,
)
