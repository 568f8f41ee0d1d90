"""IEC 62047-20 results page as data: the characteristics grouped as in its clause 5
(scale factor 5.1, cross-axis 5.2, bias 5.3, noise 5.4, frequency band 5.5, resolution
5.6)."""

GROUPS = (
    (1, "Scale factor (5.1)", "标度因数 (5.1)", ("scale_factor", "initial_sf_variation",
                                               "sf_temperature_coefficient", "ratiometric_error",
                                               "linearity", "sf_stability", "symmetry")),
    (2, "Cross-axis sensitivity (5.2)", "交叉轴灵敏度 (5.2)", ("cross_axis",)),
    (3, "Bias (5.3)", "零偏 (5.3)", ("bias", "initial_bias_variation", "bias_repeatability",
                                    "bias_drift_after_power_on", "bias_temperature_coefficient",
                                    "bias_ratiometric_error", "bias_hysteresis", "g_sensitivity",
                                    "startup_time")),
    (4, "Output noise (5.4)", "输出噪声 (5.4)", ("inband_noise", "broadband_noise", "arw",
                                                "bias_instability")),
    (5, "Frequency band (5.5)", "频带 (5.5)", ("frequency_band",)),
    (6, "Resolution (5.6)", "分辨率 (5.6)", ("resolution",)),
)

TITLES_ZH = {
    "scale_factor": "标度因数", "initial_sf_variation": "标度因数初始偏差",
    "sf_temperature_coefficient": "标度因数温度系数", "ratiometric_error": "标度因数比例误差",
    "linearity": "线性度", "sf_stability": "标度因数稳定性", "symmetry": "标度因数对称性",
    "cross_axis": "交叉轴灵敏度", "bias": "零偏", "bias_repeatability": "零偏重复性",
    "bias_temperature_coefficient": "零偏温度系数", "initial_bias_variation": "零偏初始偏差",
    "bias_drift_after_power_on": "上电后零偏漂移", "startup_time": "启动时间", "inband_noise": "带内噪声",
    "arw": "角度随机游走", "bias_instability": "零偏不稳定性", "frequency_band": "频带",
    "bias_ratiometric_error": "零偏比例误差", "bias_hysteresis": "零偏迟滞",
    "g_sensitivity": "线性加速度灵敏度", "broadband_noise": "宽带噪声", "resolution": "分辨率",
}

HEADING = ("MEMS gyroscope test results (IEC 62047-20)", "MEMS陀螺仪测试结果 (IEC 62047-20)")

#: The recalibration statement: IEC 62047-20 is a test method and sets no interval.
RECAL = ("Recalibration interval: decided by the user (IEC 62047-20 is a test method and sets "
         "none).", "复校时间间隔由用户自行确定（IEC 62047-20 为试验方法标准，未作规定）。")

#: Where the rule to state U with each result comes from: IEC 62047-20 is a test method and
#: has none; the certificate follows JJF 1535 clause 8 k) and says so.
U_CLAUSE = ("IEC 62047-20 sets no rule for it; stated as JJF 1535 clause 8 k) asks",
            "IEC 62047-20 未作规定，按 JJF 1535 第8章 k) 给出")
