"""The certificate's content of ACME RC-1 (rendered by gonio's per-item certificate)."""

#: (group number, English heading, Chinese heading, item keys in order)
GROUPS = ((1, "Scale factor and bias", "标度因数与零偏", ("scale_factor", "bias", "asymmetry")),)
#: Item names in Chinese.
TITLES_ZH = {"scale_factor": "标度因数", "bias": "零偏", "asymmetry": "标度因数不对称度"}
#: Page title.
HEADING = ("Rate gyro rate-table check results", "速率陀螺速率转台检查结果")
#: The clause that says how U is stated.
U_CLAUSE = ("ACME RC-1 clause 5", "ACME RC-1 第5条")
#: Its forward/reverse figure: the asymmetry item holds each direction's scale factor
#: (details K_pos, K_neg); the points are drawn as the output less K̄·Ω.
CW_CCW = {"item": "asymmetry", "cw": ("K_pos", None), "ccw": ("K_neg", None),
          "null_output_off": False, "ylabel": "y_j − K̄·Ω_j (mV)", "title": "asym"}
