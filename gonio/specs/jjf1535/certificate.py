"""JJF 1535-2015 Annex B (Fig. B.1), "MEMS gyroscope calibration results", as data.

The inner page groups the fifteen items: 1 scale factor (five items), 2 bias (five),
3 threshold, 4 resolution, 5 warm-up time, 6 angle random walk, 7 bandwidth. Annex B
has no uncertainty line; clause 8 k) requires one, so the certificate shows U (k) beside
each result that has a budget. The rendering is :mod:`gonio.report.rate_certificate`.
"""

#: (group number, English heading, Chinese heading, item keys in order)
GROUPS = (
    (1, "Scale factor", "标度因数", ("scale_factor", "nonlinearity", "asymmetry",
                                    "sf_repeatability", "sf_temperature_sensitivity")),
    (2, "Bias", "零偏", ("bias", "bias_stability", "bias_repeatability", "g_sensitivity",
                        "bias_temperature_sensitivity")),
    (3, "Threshold", "阈值", ("threshold",)),
    (4, "Resolution", "分辨率", ("resolution",)),
    (5, "Warm-up time", "准备时间", ("warmup_time",)),
    (6, "Angle random walk", "角度随机游走", ("angle_random_walk",)),
    (7, "Bandwidth", "带宽", ("bandwidth",)),
)

#: Item names in Chinese (the specification's terms).
TITLES_ZH = {
    "scale_factor": "标度因数", "nonlinearity": "标度因数非线性度", "asymmetry": "标度因数不对称度",
    "sf_repeatability": "标度因数重复性", "sf_temperature_sensitivity": "标度因数温度灵敏度",
    "threshold": "阈值", "resolution": "分辨率", "bias": "零偏", "warmup_time": "准备时间",
    "bias_stability": "零偏稳定性", "bias_repeatability": "零偏重复性",
    "g_sensitivity": "零偏加速度灵敏度", "angle_random_walk": "角度随机游走系数",
    "bias_temperature_sensitivity": "零偏温度灵敏度", "bandwidth": "带宽",
}

#: Page title.
HEADING = ("MEMS gyroscope calibration results", "微机电(MEMS)陀螺仪校准结果")

#: The recalibration statement (JJF 1535-2015 clause 9: one year recommended; the owner may
#: decide from the instrument's use).
RECAL = ("Recalibration interval: one year recommended; the owner may decide from the "
         "instrument's use (JJF 1535-2015 clause 9).",
         "复校时间间隔建议为1年；使用者可根据实际使用情况自主决定（JJF 1535-2015 第9章）。")
