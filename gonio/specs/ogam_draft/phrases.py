"""The optical draft's certificate phrases and display settings, as data (no imports): the
significant digits of each item without its own uncertainty, the items stated at U's decimal
place, the Chinese form of each "reading taken" note and of each budget source, and the
English form of its Chinese title. The rendering modules (:mod:`.stated`, :mod:`.dcc`,
:mod:`.certificate_pages`) read them."""

from __future__ import annotations

#: Significant digits shown for each item without its own uncertainty.
#: K is stable to ~1e-7 (its nonlinearity), so 8 digits carry information.
ITEM_SIG_DIGITS: dict[str, int] = {
    "scale_factor": 8, "scale_factor_nonlinearity": 3, "zero_stability": 3,
    "angle_deviation": 3, "repeatability": 3, "rate_consistency": 3,
    "pointing_consistency": 3,
}


#: Items shown to the decimal place of the expanded uncertainty U (JCGM 100 7.2.6).
ITEMS_AT_U_PLACE: tuple[str, ...] = ("angle_deviation", "repeatability")


#: Chinese form of each "reading taken" note (by its clause prefix) and of the budget's sources
#: (by symbol). A note or source without an entry is a test failure (tests/test_certificate.py).
READING_NOTES_ZH: dict[str, str] = {
    "7.3:": "7.3：零位稳定性读数的个数和间隔由校准方案规定（默认 15 个，间隔 5 min）；结果为 "
            "B_s = s(M)/T，并同时给出 (max M − min M)/T（定义3.3）；T 为首末读数的时间间隔。",
    "7.4:": "7.4：每个测回自 0° 起，两读数同时清零；到位后固定延时读数，自起动起 0.5 min 内完成"
            "（附录A.1）；E_i 为各组的平均值，E = ± max|E_i| 并给出其符号。",
    "7.6/7.7:": "7.6/7.7：公式中不清楚的分母理解为参考状态（60 (°)/s，轴向朝上）整周 360° 测回的"
                "测得角度；总是同时给出以 ″ 表示的极差 max E − min E。",
    "Annex A.4.4:": "附录A.4.4：u(r) 取本次校准自身重复测量（7.5）各校准点贝塞尔标准偏差的最大值。",
    "Annex A.4.2:": "附录A.4.2：u(φ_e) 采用草案的椭圆投影倾斜模型；同时给出刚体模型（倾斜为 cos ψ "
                    "因子，被标度因数吸收）。",
    "Annex A.4.4 (not applied):": "附录A.4.4（未采用）：本次校准没有自身的重复测量系列；u(r) 取"
                                  "校准方案 annex_a.repeatability_arcsec 的给定值（B类）。",
    "Annex A.4.3:": "附录A.4.3：u(B_E) 按本次实际采用的 7.4 读数中自清零至读数的最长时间计算"
                    "（而非 0.5 min 的上限）。",
}


BUDGET_SOURCES_ZH: dict[str, str] = {
    "P": "标准转台定位误差（A.4.1）",
    "phi_e": "敏感平面与台面不平行（A.4.2）",
    "B_E": "零位漂移（A.4.3）",
    "r": "重复性（A.4.4）",
    "K_P": "7.1 各停位转台误差经标度因数传入 E",
    "K_r": "7.1 读数分散性经标度因数传入 E",
    "tilt_E": "倾斜与地速耦合（第7章前言地速补偿与A.1倾斜限）",
}


#: English form of Chinese titles, used when no CJK font is installed (the en certificate).
TITLES_EN: dict[str, str] = {
    "光学陀螺测角仪校准规范": "Calibration Specification for Optical Gyroscope Angle "
                              "Measuring Instrument",
}



#: The tilt × Earth-rate coupling's sentence under the equal-division table, by the analysis'
#: ``reason`` (gonio.specs.ogam_draft.equal_division.CouplingFit), English and Chinese; ``{amp}`` its
#: amplitude Ω⊥ tan ψ (″/s), ``{eff}`` its largest effect on a reading (″), ``{cond}`` the
#: condition number, ``{size}`` its size at the tilt bound (″; the bracketed part only where
#: that size is known).
COUPLING_TEXT: dict[str, dict[str, str]] = {
    "estimated": {
        "en": "tilt × Earth-rate coupling estimated jointly with the table and goniometer "
              "errors (nuisance, first harmonic of the absolute position growing with the time "
              "since zeroing) and removed (Ω⊥ tan ψ = {amp}″/s, largest effect on a reading "
              "{eff}″)",
        "zh": "倾斜×地球自转耦合与转台误差、测角仪误差联合估计（作为干扰参数：随清零后时间增长的"
              "绝对位置一次谐波）并已扣除（Ω⊥ tan ψ = {amp}″/s，对单个读数的最大影响 {eff}″）"},
    "not_separable": {
        "en": "the coupling cannot be separated from the table and goniometer errors "
              "(condition number {cond}); it is not in the result",
        "zh": "倾斜×地球自转耦合无法与转台误差、测角仪误差分离（条件数 {cond}），未计入结果"},
    "no_times": {
        "en": "the coupling cannot be estimated: the equal_division rows have no time_s; "
              "it is not in the result",
        "zh": "倾斜×地球自转耦合无法估计：等分平均法读数没有 time_s 列，未计入结果"},
    "size": {"en": ": up to {size}″ at the tilt bound", "zh": "；在倾斜限值下最大约 {size}″"},
    "size_no_times": {"en": " (up to about {size}″ at the tilt bound)",
                      "zh": "（在倾斜限值下最大约 {size}″）"},
}
