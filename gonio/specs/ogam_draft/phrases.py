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
    "Annex A.4.4:": "附录A.4.4：草案附录A的评定中 u(r) 取本次校准自身重复测量（7.5）各校准点贝塞尔"
                    "标准偏差的最大值；物理模型评定取各点 n 组平均值的噪声（由 7.4 各组数据的噪声模型按该点时刻"
                    "求得，或取此 u(r)/√n）。",
    "Annex A.4.2:": "附录A.4.2：u(φ_e) 采用草案的椭圆投影倾斜模型；同时给出刚体模型（倾斜为 cos ψ "
                    "因子，被标度因数吸收）。",
    "Annex A.4.4 (not applied):": "附录A.4.4（未采用）：本次校准没有自身的重复测量系列；u(r) 取"
                                  "校准方案 annex_a.repeatability_arcsec 的给定值（B类）。",
    "Annex A.4.3:": "附录A.4.3：u(B_E) 按本次实际采用的 7.4 读数中自清零至读数的最长时间计算"
                    "（而非 0.5 min 的上限），用于草案附录A的评定；物理模型评定取各点"
                    "自身的时间。",
}

#: The draft's virtual instruments and table (protocols/benches: rlg, fog, table-precision) in
#: Chinese, for its DCC's zh texts.
BENCH_NAMES_ZH: dict[str, str] = {
    "RLG goniometer (virtual)": "激光陀螺测角仪（虚拟）",
    "FOG goniometer (virtual)": "光纤陀螺测角仪（虚拟）",
    "precision low-speed rotary table (virtual)": "精密低速转台（虚拟）",
}

#: The names its DCC gives its per-point tables (:mod:`.dcc`), in Chinese.
DCC_NAMES_ZH: dict[str, str] = {
    "per-point table": "逐点数据表",
    "table rate": "转台角速度",
}


BUDGET_SOURCES_ZH: dict[str, str] = {
    "P": "标准转台定位误差（A.4.1）",
    "phi_e": "敏感平面与台面不平行（A.4.2）",
    "B_E": "零位漂移（A.4.3）",
    "r": "重复性（A.4.4）",
    "K_P": "7.1 各停位转台误差经标度因数传入 E",
    "K_r": "7.1 读数分散性经标度因数传入 E",
    "tilt_E": "倾斜与地速耦合（第7章前言地速补偿与A.1倾斜限）",
    "tilt_Em": "倾斜与地速耦合按现场实测倾斜修正后的修正不确定度（由倾斜估计的协方差传播）",
}


#: The physical budget's per-point forms of the annex lines (their English source ends in
#: "[physical budget…]"; the draft's reading keeps BUDGET_SOURCES_ZH).
BUDGET_SOURCES_PHYSICAL_ZH: dict[str, str] = {
    "P": "转台定位误差：该点、零位与 7.1 各停位，每一位置一个误差，各为最大允许误差/√3"
         "（A.4.1；经标度因数，7.1）［物理模型：P 与 K_P 合为一项］",
    "phi_e": "敏感平面与台面不平行（A.4.2）：同一安装下 7.1 的标度因数已吸收该比例误差（0）"
             "［物理模型］",
    "r": "该点自清零至读数时刻的读数噪声（由 7.4 各组数据求得），E_i 为各组的平均值，除以 √n"
         "［物理模型；草案 A.4.4 取最大标准偏差］",
    "r/sqrt(n)": "重复性（A.4.4）：草案的 u(r)，E_i 为 n 组的平均值，除以 √n［物理模型］",
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


#: The draft's screening messages (its screen module) in Chinese, the table its certificate
#: hands to :func:`gonio.report.i18n.finding_text`; each group is itself translated where it
#: can be (an axis "up", a test's item name).
FINDINGS_ZH: tuple[tuple[str, str], ...] = (
    (r"nominal_scale_factor_counts_per_deg (\S+) departs from the K the readings measure, "
     r"(\S+) counts/° \(the median of gyro_counts / table_deg; ratio (\S+), beyond (\S+)× "
     r"either way: a nominal in another unit or scale\?\); the angles are read with 7\.1's K, "
     r"no certified item uses it",
     "元数据标称标度因数 nominal_scale_factor_counts_per_deg = {1} 与读数测得的 K = {2} 脉冲数/(°)"
     "（gyro_counts / table_deg 的中位数）不符，比值 {3}，超出任一方向 {4} 倍（标称值单位或量级有误？）；"
     "角度按 7.1 的 K 换算，无校准项目使用该标称值"),
    (r"(\w+) at (\S+) °/s, axis (\w+): not a condition of the protocol's programme \((.+?)\); "
     r"(\d+) readings, lines (\d+)–(\d+), all set aside",
     "{1}，{2} °/s，{3}轴：不是校准方案（{4}）规定的测量条件；第 {6}–{7} 行共 {5} 个读数均剔除"),
    (r"(\w+) at (\S+) °/s, axis (\w+): not a condition of the protocol's programme \((.+?)\)",
     "{1}，{2} °/s，{3}轴：不是校准方案（{4}）规定的测量条件"),
    (r"(\w+) series (.+?) (?:is not one of|are not among) the protocol's (\d+) series \((.+?)\); "
     r"(\d+) readings, lines (\d+)–(\d+), complete, measured beyond the programme: used",
     "{1} 第 {2} 系列超出校准方案（{4}）的 {3} 个系列，测回完整，予以采用；第 {6}–{7} 行共 {5} 个读数"),
    (r"(\w+) series (.+?) (?:is not one of|are not among) the protocol's (\d+) series \((.+?)\); "
     r"(\d+) readings, lines (\d+)–(\d+), all set aside",
     "{1} 第 {2} 系列不属于校准方案（{4}）的 {3} 个系列；第 {6}–{7} 行共 {5} 个读数均剔除"),
    (r"(\w+) series (.+?) (?:is not one of|are not among) the protocol's (\d+) series \((.+?)\)$",
     "{1} 第 {2} 系列不属于校准方案（{4}）的 {3} 个系列"),
    (r"(\w+) round (\d+) is not one of the protocol's (\d+) rounds \((.+)\)",
     "{1} 第 {2} 测回不属于校准方案（{4}）的 {3} 个测回"),
    (r"(\w+) round (\d+): table_deg (\S+) differs from the protocol's (\S+)° \(tolerance (\S+)°\)",
     "{1} 第 {2} 测回：转台角 {3}° 与校准方案的 {4}° 不符（允差 {5}°）"),
    (r"(\w+) round (\d+): read (\S+) s after zeroing, beyond the protocol's "
     r"max_time_to_reading_s = (\S+) s \(Annex A\.1\)",
     "{1} 第 {2} 测回：清零后 {3} s 才读数，超过校准方案规定的 {4} s（附录A.1）"),
    (r"(\w+) round (\d+): read (\S+) s after zeroing, beyond Annex A\.1's 0\.5 min \((\S+) s; "
     r"the protocol sets no max_time_to_reading_s, only an explicit one widens it\) "
     r"\(Annex A\.1\)",
     "{1} 第 {2} 测回：清零后 {3} s 才读数，超过附录A.1 的 0.5 min（{4} s；校准方案未另行规定）"),
    (r"(.+) round (\d+): indicated − table angle (\S+)″ departs from the condition's median "
     r"(\S+)″ by (\S+)″ \(> (\S+)″\) \(K_ref = (\S+) counts/° from the other readings\)",
     "{1}，第 {2} 测回：示值 − 转台角 = {3}″，偏离该条件的中位数 {4}″ 达 {5}″（> {6}″；"
     "K_ref = {7} 脉冲数/(°)，由其余读数求得）"),
    (r"(.+) round (\d+): indicated − table angle (\S+)″ departs from the condition's median "
     r"(\S+)″ by (\S+)″ \(> (\S+)″\)",
     "{1}，第 {2} 测回：示值 − 转台角 = {3}″，偏离该条件的中位数 {4}″ 达 {5}″（> {6}″）"),
    (r"(.+) round (\d+): indicated − table angle (\S+)″ departs from the round's median "
     r"(\S+)″ by (\S+)″ \(> (\S+)″\) \(K_ref = (\S+) counts/° from the other readings\)",
     "{1}，第 {2} 测回：示值 − 转台角 = {3}″，偏离该测回的中位数 {4}″ 达 {5}″（> {6}″；"
     "K_ref = {7} 脉冲数/(°)，由其余读数求得）"),
    (r"(.+) round (\d+): indicated − table angle (\S+)″ departs from the round's median "
     r"(\S+)″ by (\S+)″ \(> (\S+)″\)",
     "{1}，第 {2} 测回：示值 − 转台角 = {3}″，偏离该测回的中位数 {4}″ 达 {5}″（> {6}″）"),
    (r"(.+) round (\d+): indicated − table angle (\S+)″ departs from the fit its condition's other readings draw, each reading less the 7\.4 reference round's median at its angle by (\S+)″ \(> (\S+)″; s = (\S+)″ of the others, drift allowed (\S+)″\) \(K_ref = (\S+) counts/° from the other readings\)",
     "{1}，第 {2} 测回：示值 − 转台角 = {3}″，偏离该条件其余读数的拟合（各读数减去 7.4 参考测回在同一角位置的中位数） 达 {4}″（> {5}″；其余读数 s = {6}″，允许漂移 {7}″；K_ref = {8} 脉冲数/(°)，由其余读数求得）"),
    (r"(.+) round (\d+): indicated − table angle (\S+)″ departs from the fit its condition's other readings draw, each reading less the 7\.4 reference round's median at its angle by (\S+)″ \(> (\S+)″; s = (\S+)″ of the others, drift allowed (\S+)″\)",
     "{1}，第 {2} 测回：示值 − 转台角 = {3}″，偏离该条件其余读数的拟合（各读数减去 7.4 参考测回在同一角位置的中位数） 达 {4}″（> {5}″；其余读数 s = {6}″，允许漂移 {7}″）"),
    (r"(.+) round (\d+): indicated − table angle (\S+)″ departs from the fit its condition's other readings draw by (\S+)″ \(> (\S+)″; s = (\S+)″ of the others, drift allowed (\S+)″\) \(K_ref = (\S+) counts/° from the other readings\)",
     "{1}，第 {2} 测回：示值 − 转台角 = {3}″，偏离该条件其余读数的拟合 达 {4}″（> {5}″；其余读数 s = {6}″，允许漂移 {7}″；K_ref = {8} 脉冲数/(°)，由其余读数求得）"),
    (r"(.+) round (\d+): indicated − table angle (\S+)″ departs from the fit its condition's other readings draw by (\S+)″ \(> (\S+)″; s = (\S+)″ of the others, drift allowed (\S+)″\)",
     "{1}，第 {2} 测回：示值 − 转台角 = {3}″，偏离该条件其余读数的拟合 达 {4}″（> {5}″；其余读数 s = {6}″，允许漂移 {7}″）"),
    (r"zero_stability \(7\.3\) series (\d+): (\d+) of the protocol's (\d+) readings (\S+) s "
     r"apart; round\(s\) (.+) missing; B_s rests on the (\d+) readings read, T = (\S+) s "
     r"from the first to the last",
     "零位稳定性（7.3）第 {1} 组：校准方案规定 {3} 个读数（间隔 {4} s），读得 {2} 个；第 {5} "
     "个读数缺失；B_s 依据所读的 {6} 个读数，T = {7} s（首末读数之间）"),
    (r"zero_stability \(7\.3\) series (\d+) round (\d+): read at (\S+) s, the schedule's "
     r"(\S+) s \(round 1 at (\S+) s, (\S+) s apart\); used as read, T = (\S+) s from the "
     r"first to the last reading",
     "零位稳定性（7.3）第 {1} 组第 {2} 个读数：在 {3} s 读取，按计划应在 {4} s（第 1 个读数在 "
     "{5} s，间隔 {6} s）；按实际读数时刻使用，T = {7} s（首末读数之间）"),
    (r"tilt_estimate \(in-situ tilt estimate, supports A\.1\) at axis (\w+) position (\d+) "
     r"\((\S+)°\): the angle accumulated over its rest (\S+)″ departs from the fit the other "
     r"positions draw by (\S+)″ \(> (\S+)″; s = (\S+)″ of the others, drift allowed (\S+)″\); "
     r"set aside, ψ estimated from the other positions \(K_ref = (\S+) counts/° from the "
     r"rotation readings\)",
     "倾斜原位估计（支持附录A.1），{1}轴，第 {2} 位置（{3}°）：静止期间累积角 {4}″ 偏离其余位置的"
     "拟合达 {5}″（> {6}″；其余读数 s = {7}″，允许漂移 {8}″）；予以剔除，ψ 由其余位置估计"
     "（K_ref = {9} 脉冲数/(°)，由转动读数求得）"),
    (r"tilt_estimate \(in-situ tilt estimate, supports A\.1\) at axis (\w+) position (\d+) "
     r"\((\S+)°\): the angle accumulated over its rest (\S+)″ departs from the fit the other "
     r"positions draw by (\S+)″ \(> (\S+)″; s = (\S+)″ of the others, drift allowed (\S+)″\); "
     r"set aside, ψ estimated from the other positions",
     "倾斜原位估计（支持附录A.1），{1}轴，第 {2} 位置（{3}°）：静止期间累积角 {4}″ 偏离其余位置的"
     "拟合达 {5}″（> {6}″；其余读数 s = {7}″，允许漂移 {8}″）；予以剔除，ψ 由其余位置估计"),
    (r"the in-situ tilt estimate measured psi = (\S+)° \(U95 (\S+)°, interval \[(\S+), "
     r"(\S+)\]°\), beyond the stated tilt bound (\S+)° \(tilt_bound_deg, Annex A\.1\): the "
     r"mounting does not meet the bound; K and E stay corrected at the measured tilt, and every "
     r"line taken at the bound is taken at psi \+ U95 = (\S+)°",
     "倾斜原位估计测得 ψ = {1}°（U95 {2}°，区间 [{3}, {4}]°），超出所声明的倾斜限值 {5}°"
     "（tilt_bound_deg，附录A.1）：安装不满足该限值；K 和 E 仍按实测倾斜修正，原按限值计算的"
     "各不确定度分量改按 ψ + U95 = {6}° 计算"),
    (r"(\w+) at (\S+) °/s, axis (\w+): readings at lines (.+?) judged only against one another: "
     r"7\.4 does not read each of these stops at this rate and axis in (\d+) or more series, "
     r"so no repeated reference says what each position reads; the rule can single "
     r"out one departing reading, two or more hide one another and would be read as "
     r"nonlinearity \(K_l\) and in E",
     "{1}，{2} °/s，{3}轴：第 {4} 行的读数仅相互比较：7.4 未在该角速率和轴向上对这些位置各读 {5} "
     "组及以上，没有重复测量的参考说明各位置的读数；该规则只能识别一个偏离的读数，"
     "两个及以上会相互掩盖，并被当作非线性度（K_l）并计入 E"),
    (r"(\w+) at (\S+) °/s, axis (\w+): readings? at lines? (.+?) judged by no rule \((\d+) "
     r"readings?; the median rule needs 3\): a typo of any size in one of them would not have "
     r"been seen; each ″ of it moves (C_\w) \((\S+)\) by up to (\S+) (ppm|%) \(line (\d+)\), "
     r"and by up to (\S+) (?:ppm|%) more where it changes the sign of the condition's extreme E",
     "{1}，{2} °/s，{3}轴：第 {4} 行的读数未经任何规则判别（{5} 个读数；中位数规则至少需要 3 个）："
     "其中一个读数无论多大的录入错误都无法被发现；该错误每 1″ 使 {6}（{7}）最多改变 {8} {9}"
     "（第 {10} 行），若使该条件极值 E 的符号改变，最多再改变 {11} {9}"),
    (r"(\w+) at (\S+) °/s, axis (\w+): readings at lines (.+?) judged only by the median rule "
     r"\(fewer than (\d+) readings; its floor (\S+)″, widened by the readings' own spread\): a "
     r"typo in one of them of up to (\S+)″ \(line (\d+), (\S+)°\) would not have been seen; it "
     r"would move E at its position by up to (\S+)″ and (C_\w) \((\S+)\) by up to (\S+) "
     r"(ppm|%)",
     "{1}，{2} °/s，{3}轴：第 {4} 行的读数仅按中位数规则判别（读数少于 {5} 个；其下限 {6}″，"
     "随读数自身的分散而加宽）：其中一个读数若有不超过 {7}″ 的录入错误（第 {8} 行，{9}°）将"
     "无法被发现；它会使该位置的 E 最多改变 {10}″，{11}（{12}）最多改变 {13} {14}"),
    (r"(\w+) at (\S+) °/s, axis (\w+): readings? at lines? (.+?) judged by no rule \((\d+) "
     r"readings?; the median rule needs 3\): a typo of any size in one of them would not have "
     r"been seen; each ″ of it moves K by up to (\S+) ppm and K_l by up to (\S+) % \(line "
     r"(\d+), (\S+)°\), and E and every item computed with K with them",
     "{1}，{2} °/s，{3}轴：第 {4} 行的读数未经任何规则判别（{5} 个读数；中位数规则至少需要 3 个）："
     "其中一个读数无论多大的录入错误都无法被发现；该错误每 1″ 使 K 最多改变 {6} ppm、K_l 最多"
     "改变 {7} %（第 {8} 行，{9}°），E 及所有用 K 计算的项目随之改变"),
    (r"(\w+) at (\S+) °/s, axis (\w+): readings at lines (.+?) judged only by the median rule "
     r"\(fewer than (\d+) readings; its floor (\S+)″, widened by the readings' own spread\): a "
     r"typo in one of them of up to (\S+)″ \(line (\d+), (\S+)°\) would not have been seen; it "
     r"would move K by up to (\S+) ppm and K_l by up to (\S+) %, and E and every item computed "
     r"with K with them",
     "{1}，{2} °/s，{3}轴：第 {4} 行的读数仅按中位数规则判别（读数少于 {5} 个；其下限 {6}″，"
     "随读数自身的分散而加宽）：其中一个读数若有不超过 {7}″ 的录入错误（第 {8} 行，{9}°）将"
     "无法被发现；它会使 K 最多改变 {10} ppm、K_l 最多改变 {11} %，E 及所有用 K 计算的项目随之改变"),
    (r"(\w+) at (\S+) °/s, axis (\w+)", "{1}，{2} °/s，{3}轴"),
    (r"zero_stability series (\d+)", "零位稳定性第 {1} 组"),
    (r"(\w+) \((\S+)\): the programme's condition (\S+) °/s, axis (\w+) has no reading; the "
     r"item is not stated \((\S+) compares E at every condition of the programme\)",
     "{1}（{2}）：校准方案的测量条件 {3} °/s、{4}轴没有读数；该项目不予给出（{5} "
     "要求在校准方案的每个测量条件下比较 E）"),
    (r"(\w+) \((\S+)\): the programme's condition (\S+) °/s, axis (\w+) has no reading",
     "{1}（{2}）：校准方案的测量条件 {3} °/s、{4}轴没有读数"),
    (r"(\w+) \((\S+)\) at (\S+) °/s, axis (\w+): round (\d+) \((\S+)°\) is missing from every "
     r"series; K rests on (\d+) of the programme's (\d+) rounds \(its table bound over all "
     r"(\d+)\); K_l is not stated \(7\.2 is the range over every round of the programme\)",
     "{1}（{2}），{3} °/s，{4}轴：第 {5} 测回（{6}°）在各组中均缺失；K 仅依据校准方案 {8} "
     "个测回中的 {7} 个（其转台误差限按全部 {9} 个测回计算）；K_l 不予给出（7.2 为校准方案"
     "全部测回上的极差）"),
    (r"(\w+) \((\S+)\) at (\S+) °/s, axis (\w+): round (\d+) \((\S+)°\) is missing from every "
     r"series; the item rests on (\d+) of the programme's (\d+) rounds",
     "{1}（{2}），{3} °/s，{4}轴：第 {5} 测回（{6}°）在各组中均缺失；该项目仅依据校准方案 {8} "
     "个测回中的 {7} 个"),
    (r"(\w+) \((\S+)\) at (\S+) °/s, axis (\w+): round (\d+) \((\S+)°\) is missing from every "
     r"series; the item is not stated \((\S+) compares every condition over the same positions\)",
     "{1}（{2}），{3} °/s，{4}轴：第 {5} 测回（{6}°）在各组中均缺失；该项目不予给出（{7} "
     "要求各测量条件在相同的位置上比较）"),
)


#: Why an item was not measured (the draft's items module), in Chinese: the table its
#: certificate and DCC hand to :func:`gonio.report.i18n.reason_text` and the translator.
REASONS_ZH: tuple[tuple[str, str], ...] = (
    (r"no (\w+) rows in file", "文件中没有 {1} 数据行"),
    (r"scale factor not measured: (.+)", "标度因数未测：{1}"),
    (r"needs at least 2 scale_factor rounds, file has 1", "至少需要 2 个标度因数测回，文件只有 1 个"),
    (r"zero_stability needs at least 2 readings in a series", "零位稳定性每组至少需要 2 个读数"),
    (r"no angle_deviation rows at the 7\.4 condition \((.+)\)", "没有 7.4 测量条件（{1}）下的 "
     "angle_deviation 数据行"),
    (r"repeatability needs at least 2 angle_deviation series, file has 1",
     "重复性至少需要 2 组 angle_deviation 数据，文件只有 1 组"),
    (r"the series agree to the last digit at every point \(a copied or filled column, or "
     r"readings rounded coarser than their scatter\): R would be certified as 0",
     "各测量点各组读数末位完全相同（复制或填充的列，或读数的舍入粗于其分散）：R 将被定为 0"),
    (r"no (\w+) rows at (.+)", "没有 {2} 下的 {1} 数据行"),
    (r"no reference condition \((.+)\): neither (\w+) nor angle_deviation rows there",
     "没有参考条件（{1}）：该条件下既无 {2} 也无 angle_deviation 数据行"),
    (r"(\S+) needs at least 2 conditions, file has only (.+)", "{1} 至少需要 2 个测量条件，文件只有 {2}"),
    (r"(\S+) needs at least 2 complete conditions", "{1} 至少需要 2 个完整的测量条件"),
    (r"no calibration position common to every condition", "各测量条件没有共同的校准位置"),
    (r"(\S+) compares E over the same calibration positions at every condition: (.+); not "
     r"stated from fewer conditions or positions \(read the missing position again\)",
     "{1} 要求各测量条件在相同的校准位置上比较 E：{2}；不以较少的测量条件或位置给出结果"
     "（请补测缺失的位置）"),
    (r"(\S+) compares E at every condition of the programme: (.+) has no reading \((\d+) "
     r"of (\d+) conditions read\); not stated from fewer conditions \(read the missing "
     r"condition\)",
     "{1} 要求在校准方案的每个测量条件下比较 E：{2} 没有读数（校准方案 {4} 个测量条件中仅读得 "
     "{3} 个）；不以较少的测量条件给出结果（请补测缺失的测量条件）"),
    (r"7\.2 is the range of K_i over every round of the programme: (.+) deg has no reading "
     r"\((\d+) of (\d+) rounds read\); not stated from fewer rounds \(read the missing "
     r"round\)",
     "7.2 为校准方案全部测回上 K_i 的极差：{1}° 没有读数（校准方案 {3} 个测回中仅读得 {2} 个）；"
     "不以较少的测回给出结果（请补测缺失的测回）"),
    (r"(.+) lacks (.+) deg \((\d+) of (\d+) positions\)", "{1} 缺少 {2}°（{4} 个位置中仅有 {3} 个）"),
    (r"(\S+) deg/s, axis (\w+)", "{1} °/s，{2}轴"),
    (r"(\S+) deg/s", "{1} °/s"),
    (r"axis (\w+)", "{1}轴"),
)


#: The draft's own certificate labels, {key: {"en": …, "zh": …}}, beside the shared ones
#: (:func:`gonio.report.i18n.labels` ``own``; the translator of its findings, reasons and DCC
#: reads them too): its seven items (Annex B order, the draft's own Chinese terms), their
#: notes, its figures, its method, results and detail tables.
LABELS: dict[str, dict[str, str]] = {
    "results": {"en": "Results of calibration (Annex B)", "zh": "校准结果（附录B）"},
    "readings_taken": {"en": "Readings taken of the draft's ambiguities",
                       "zh": "对规范草案中不明确之处的理解"},
    "beyond_draft": {"en": "beyond the draft", "zh": "超出草案"},
    "U_line": {"en": "Uncertainty of the angle-position deviation: U = {U}″, k = {k}",
               "zh": "角位置偏差的测量不确定度：U = {U}″，k = {k}"},
    "K_as_mounted": {"en": "The scale factor K is stated as mounted: sensing plane within {psi}° "
                           "of the table plane (Annex A.1). The instrument's own K (sensing axis "
                           "along the rotation axis) is larger by up to {ppm} ppm (1/cos ψ − 1); "
                           "this is not included in U.",
                     "zh": "标度因数 K 为安装状态下的值：敏感平面与转台台面的夹角不超过 {psi}°"
                           "（附录A.1）。仪器自身的 K（敏感轴沿转轴）最多大 {ppm} ppm"
                           "（1/cos ψ − 1），未计入 U。"},
    "K_as_mounted_measured": {
        "en": "The scale factor K is stated as mounted. The tilt of the sensing axis from the "
              "rotation axis was measured in situ (beyond the draft): ψ = {psi}° (U = {U}°, "
              "k = {k}). The instrument's own K (sensing axis along the rotation axis) is larger "
              "by 1/cos ψ − 1 = {ppm} ppm (95 % interval [{lo}, {hi}] ppm; the A.1 bound of "
              "{bound}° would allow up to {bppm} ppm); this is not included in U.",
        "zh": "标度因数 K 为安装状态下的值。敏感轴相对转轴的倾角经现场测量（超出草案）："
              "ψ = {psi}°（U = {U}°，k = {k}）。仪器自身的 K（敏感轴沿转轴）大 "
              "1/cos ψ − 1 = {ppm} ppm（95 % 区间 [{lo}, {hi}] ppm；按附录A.1 的限值 {bound}° "
              "最多大 {bppm} ppm），未计入 U。"},
    "K_temperature_bound": {
        "en": "U(K) holds for a chamber within ±{tol} °C of the reference temperature (Table 2) "
              "and a scale-factor temperature coefficient |α_K| ≤ {b} ppm/°C: {src}.",
        "zh": "U(K) 适用于温度偏离参考温度不超过 ±{tol} °C 的环境（表2），标度因数温度系数 "
              "|α_K| ≤ {b} ppm/°C：{src}。"},
    "K_temperature_logged": {
        "en": "U(K) holds for the chamber temperature the readings log, {t} °C{over} ({dt} °C "
              "from the reference {ref} °C, Table 2; thermometer MPE ±{m} °C), and a "
              "scale-factor temperature coefficient |α_K| ≤ {b} ppm/°C: {src}.",
        "zh": "U(K) 适用于读数文件记录的环境温度 {t} °C{over}（与参考温度 {ref} °C 相差 {dt} °C，"
              "表2；测温仪最大允许误差 ±{m} °C），标度因数温度系数 |α_K| ≤ {b} ppm/°C：{src}。"},
    "K_T_over_column": {"en": " (mean over the 7.1 rounds)", "zh": "（7.1 各轮平均值）"},
    "K_T_source_metadata": {"en": "the instrument's bound stated in the readings",
                            "zh": "读数文件给出的仪器自身限值"},
    "K_T_source_protocol-rlg": {"en": "the protocol's default for an RLG",
                                "zh": "规程对激光陀螺的默认值"},
    "K_T_source_protocol-fog": {"en": "the protocol's default for a FOG",
                                "zh": "规程对光纤陀螺的默认值"},
    "K_T_source_protocol-larger": {"en": "gyro type not stated, the larger of the protocol's "
                                         "RLG and FOG defaults",
                                   "zh": "未给出陀螺类型，取规程激光陀螺与光纤陀螺默认值中的较大者"},
    "std_mpe": {"en": "MPE ±{v}″", "zh": "最大允许误差 ±{v}″"},
    "u_c_line": {"en": "combined standard uncertainty u_c = {u}″ (Annex A.6)",
                 "zh": "合成标准不确定度 u_c = {u}″（附录A.6）"},
    "budget": {"en": "Uncertainty budget (Annex A)", "zh": "不确定度分量（附录A）"},
    "eda": {"en": "Rotary-table calibration by equal-division averaging (IEC 62047-20 Annex A.3)",
            "zh": "等分平均法转台校准（IEC 62047-20 附录 A.3）"},
    "eda_note": {"en": "{n} starts, {m} points per revolution, {r} repeat(s); table error "
                       "indicated − true with Σt = 0; goniometer error as a function of the angle "
                       "turned; standard uncertainties from the residuals ({noise} reading-error "
                       "model). Table harmonics whose order is a multiple of n are unobservable.",
                 "zh": "起始位置 {n} 个，每周 {m} 点，重复 {r} 次；转台误差为示值减真值，Σt = 0；"
                       "测角仪误差为转角的函数；标准不确定度由残差求得（{noise} 读数误差模型）。"
                       "阶次为 n 倍数的转台谐波不可观测。"},
    "eda_position": {"en": "table position (°)", "zh": "转台位置（°）"},
    "eda_table": {"en": "table error (″)", "zh": "转台误差（″）"},
    "eda_turned": {"en": "angle turned (°)", "zh": "转角（°）"},
    "eda_gonio": {"en": "goniometer error (″)", "zh": "测角仪误差（″）"},
    "eda_closure": {"en": "Full-circle closure: goniometer error at 360° = {v}″ ± {u}″",
                    "zh": "整周闭合：测角仪 360° 误差 = {v}″ ± {u}″"},
    "scale_factor": {"en": "Scale factor K", "zh": "标度因数 K"},
    "scale_factor_nonlinearity": {"en": "Scale-factor nonlinearity K_l",
                                  "zh": "标度因数非线性度 K_l"},
    "zero_stability": {"en": "Zero stability B_s", "zh": "零位稳定性 B_s"},
    "angle_deviation": {"en": "Angle-position deviation E", "zh": "角位置偏差 E"},
    "repeatability": {"en": "Angle-position repeatability R", "zh": "角位置重复性 R"},
    "rate_consistency": {"en": "Rate consistency C_v", "zh": "速率一致性 C_v"},
    "pointing_consistency": {"en": "Pointing consistency C_g", "zh": "指向一致性 C_g"},
    "note_zero_range": {"en": "range/T (definition 3.3): {v} °/h", "zh": "极差/T（定义3.3）：{v} (°)/h"},
    "note_zero_model": {"en": "noise model of the 7.3 record (beside, not stated): {v} °/h",
                        "zh": "7.3 连续记录的噪声模型估计（并列给出，不作结果）：{v} (°)/h"},
    "note_kl_draft": {"en": "the draft's range as measured (beside, not stated): {v} %",
                      "zh": "按草案公式的测得极差（并列给出，不作结果）：{v} %"},
    "note_k_tilt": {"en": "corrected for the measured tilt ψ = {p}° (U = {up}°) at azimuth {a}° "
                          "(U = {ua}°), beyond the draft; the 7.1 mean uncorrected: {v}",
                    "zh": "已按实测倾斜修正（草案以外）：ψ = {p}°（U = {up}°），方位角 {a}°"
                          "（U = {ua}°）；未修正的 7.1 平均值：{v}"},
    "note_k_table": {"en": "table error at the 7.1 positions corrected by the table "
                           "calibration {f} (its u(K) {u} ppm), beyond the draft",
                     "zh": "7.1 各位置的转台误差已按转台校准 {f} 修正（草案以外，其 u(K) 为 "
                           "{u} ppm）"},
    "note_k_table_v": {"en": "table error at the 7.1 positions corrected by the table "
                             "calibration {f} (its u(K) {u} ppm), beyond the draft; the 7.1 "
                             "mean uncorrected: {v}",
                       "zh": "7.1 各位置的转台误差已按转台校准 {f} 修正（草案以外，其 u(K) 为 "
                             "{u} ppm）；未修正的 7.1 平均值：{v}"},
    "note_e_tilt": {"en": "every E_ij corrected for the tilt × Earth-rate coupling at the "
                          "measured tilt, beyond the draft; the draft's reading as measured "
                          "(Annex A, beside, not stated): {v}″",
                    "zh": "各 E_ij 已按实测倾斜修正倾斜与地球自转角速度的耦合（草案以外）；"
                          "按草案（附录 A）的测得值（并列给出，不作结果）：{v}″"},
    "note_e_tilt_only": {"en": "every E_ij corrected for the tilt × Earth-rate coupling at the "
                               "measured tilt, beyond the draft",
                         "zh": "各 E_ij 已按实测倾斜修正倾斜与地球自转角速度的耦合（草案以外）"},
    "note_e_table": {"en": "every E_ij's reference angle corrected by the table calibration "
                           "{f} and E_ij read with the table-corrected K, beyond the draft",
                     "zh": "各 E_ij 的参考角已按转台校准 {f} 修正，并以转台误差修正后的 K "
                           "换算（草案以外）"},
    "note_e_table_nok": {"en": "every E_ij's reference angle corrected by the table calibration "
                               "{f}, beyond the draft",
                         "zh": "各 E_ij 的参考角已按转台校准 {f} 修正（草案以外）"},
    "note_e_table_v": {"en": "every E_ij's reference angle corrected by the table calibration "
                             "{f} and E_ij read with the table-corrected K, beyond the draft; "
                             "the draft's reading as measured (Annex A, beside, not stated): "
                             "{v}″",
                       "zh": "各 E_ij 的参考角已按转台校准 {f} 修正，并以转台误差修正后的 K "
                             "换算（草案以外）；按草案（附录 A）的测得值（并列给出，不作结果）："
                             "{v}″"},
    "note_e_table_v_nok": {"en": "every E_ij's reference angle corrected by the table calibration "
                                 "{f}, beyond the draft; the draft's reading as measured (Annex "
                                 "A, beside, not stated): {v}″",
                           "zh": "各 E_ij 的参考角已按转台校准 {f} 修正（草案以外）；按草案（附录 A）"
                                 "的测得值（并列给出，不作结果）：{v}″"},
    "note_range_table": {"en": "readings corrected by the table calibration {f}, its "
                               "uncertainty in place of the table's MPE, beyond the draft",
                         "zh": "读数已按转台校准 {f} 修正，以其不确定度代替转台最大允许误差"
                               "（草案以外）"},
    "note_range_table_k": {"en": "readings corrected by the table calibration {f} and read with "
                                 "the table-corrected 7.1 K, its uncertainty in place of the "
                                 "table's MPE, beyond the draft",
                           "zh": "读数已按转台校准 {f} 修正，并以转台误差修正后的 7.1 K 换算，"
                                 "以其不确定度代替转台最大允许误差（草案以外）"},
    "note_range_table_kl": {"en": "the 7.1 rounds corrected by the table calibration {f}, its "
                                  "uncertainty in place of the table's MPE, beyond the draft",
                            "zh": "7.1 各测回已按转台校准 {f} 修正，以其不确定度代替转台最大允许"
                                  "误差（草案以外）"},
    "note_e_table_part": {"en": "; not corrected (kept with the table's MPE line): E at {p}°",
                          "zh": "；未修正（保留转台最大允许误差分量）：E 在 {p}°"},
    "note_e_table_k_mpe": {"en": "; K not corrected by the table calibration (a 7.1 position "
                                 "not in it): E read with K as measured, K's part of the table "
                                 "error at the MPE",
                           "zh": "；K 未经转台校准修正（7.1 有位置不在校准中）：E 以测得的 K "
                                 "换算，K 引入的转台误差按最大允许误差计"},
    "note_cv_draft": {"en": "the draft's range as measured (beside, not stated): {v} ppm",
                      "zh": "按草案公式的测得极差（并列给出，不作结果）：{v} ppm"},
    "note_cg_draft": {"en": "the draft's range as measured (beside, not stated): {v} %",
                      "zh": "按草案公式的测得极差（并列给出，不作结果）：{v} %"},
    "note_at": {"en": "at {p}°", "zh": "位于 {p}°"},
    "below_zero": {"en": "bias-corrected estimate below zero",
                   "zh": "偏差修正后的估计值低于零"},
    "note_nominal_k": {"en": "angles read with the nominal scale factor of the readings' "
                             "metadata (no 7.1 readings): its error is not known to this "
                             "calibration and is not in the uncertainty",
                       "zh": "角度按读数元数据中的标称标度因数换算（无7.1读数）：其误差本次校准未知，"
                             "未计入不确定度"},
    "note_spread": {"en": "spread max E − min E = {v}″", "zh": "极差 max E − min E = {v}″"},
    "fig_deviation": {"en": "Fig. 1 Angle-position deviation of every series (cf. Annex Fig. A.4)",
                      "zh": "图1 各组角位置偏差曲线（参见附录图A.4）"},
    "fig_repeat": {"en": "Fig. 2 Repeatability per position (cf. Annex Fig. A.5)",
                   "zh": "图2 各位置的角位置重复性（参见附录图A.5）"},
    "fig_tilt": {"en": "Fig. 3 Tilt error at the tilt bound: elliptic model (Annex A.4.2, Fig. A.3) "
                       "and rigid-body model",
                 "zh": "图3 倾斜误差：椭圆投影模型（附录A.4.2，图A.3）与刚体模型"},
    "fig_sf": {"en": "Fig. 4 Scale factor per round (7.1)", "zh": "图4 各测回标度因数（7.1）"},
    "fig_zero": {"en": "Fig. 5 Zero-stability readings and drift (7.3)",
                 "zh": "图5 零位稳定性读数及漂移（7.3）"},
    "fig_rate": {"en": "Fig. 6 Deviation per rate (7.6)", "zh": "图6 不同速率下的角位置偏差（7.6）"},
    "fig_pointing": {"en": "Fig. 7 Deviation per axis direction (7.7)",
                     "zh": "图7 不同指向下的角位置偏差（7.7）"},
    "fig_budget": {"en": "Fig. 8 Uncertainty budget: contributions |c_i|·u_i (Annex A)",
                   "zh": "图8 不确定度分量 |c_i|·u_i（附录A）"},
    "ax_position": {"en": "table position (°)", "zh": "转台位置（°）"},
    "ax_deviation": {"en": "deviation E (″)", "zh": "偏差 E（″）"},
    "ax_std": {"en": "standard deviation s (″)", "zh": "标准偏差 s（″）"},
    "ax_tilt": {"en": "error Δ (″)", "zh": "误差 Δ（″）"},
    "ax_round_angle": {"en": "round angle θ_i (°)", "zh": "测回角度 θ_i（°）"},
    "ax_K": {"en": "K_i (counts/°)", "zh": "K_i（脉冲数/(°)）"},
    "ax_time_min": {"en": "time since first reading (min)", "zh": "距首次读数时间（min）"},
    "ax_angle_arcsec": {"en": "reading M (″)", "zh": "读数 M（″）"},
    "ax_contribution": {"en": "contribution (″)", "zh": "分量（″）"},
    "fig_u_c_beside": {"en": "u_c (not stated)", "zh": "u_c（不声明）"},
    "fig_u_other": {"en": "u (not the table)", "zh": "u（转台以外）"},
    "fig_b": {"en": "b (table's bound)", "zh": "b（转台误差界）"},
    "lg_series": {"en": "series", "zh": "组"},
    "lg_mean": {"en": "mean E_i", "zh": "平均 E_i"},
    "lg_elliptic": {"en": "elliptic model, ψ = {psi}°", "zh": "椭圆模型, ψ = {psi}°"},
    "lg_rigid": {"en": "rigid body, after 7.1 (≡ 0)", "zh": "刚体模型，经7.1标定后（≡ 0）"},
    "lg_rigid_uncal": {"en": "rigid body, uncalibrated", "zh": "刚体模型, 未标定"},
    "lg_mean_K": {"en": "K (mean)", "zh": "K（平均）"},
    "lg_drift": {"en": "linear drift {v} °/h", "zh": "线性漂移 {v} (°)/h"},
    "lg_R": {"en": "R = max", "zh": "R = 最大值"},
    "lg_reference": {"en": "(reference)", "zh": "（参考）"},
    "U_col": {"en": "Expanded uncertainty U", "zh": "扩展不确定度 U"},
    "E_note": {"en": "signed extreme {s}″ at {p}°", "zh": "带符号极值 {s}″，位于 {p}°"},
    "U_line_p": {"en": "Uncertainty of the angle-position deviation: U = {U}″, k = {k}, "
                       "coverage probability {p}",
                 "zh": "角位置偏差的测量不确定度：U = {U}″，k = {k}，包含概率{p}"},
    "U_line_points": {"en": "Uncertainty of each point's E_i (the largest of the points'): "
                            "U = {U}″, k = {k}, coverage probability {p}",
                      "zh": "各测量点 E_i 的测量不确定度（取各点中最大者）：U = {U}″，k = {k}，"
                            "包含概率{p}"},
    "U_line_points_bound": {
        "en": "Uncertainty of each point's E_i (the largest of the points', at {pos}°): "
              "U = {U}″, k = {k}, coverage probability {p} (U = k·u + b: u = {u}″ (ν = {nu}) "
              "the combined standard uncertainty of the lines other than the table's, "
              "k·u = {ku}″, plus the table's bound b = {b}″ at the point, which holds every "
              "table within the MPE)",
        "zh": "各测量点 E_i 的测量不确定度（取各点中最大者，位于 {pos}°）：U = {U}″，k = {k}，"
              "包含概率{p}（U = k·u + b：u = {u}″（ν = {nu}）为转台以外各分量的合成标准不确定度，"
              "k·u = {ku}″；b = {b}″ 为该点转台误差的界，对最大允许误差内的任何转台成立）"},
    "u_c_not_certified": {
        "en": "No combined standard uncertainty of E is certified: the table enters U by its "
              "bound b, not by a standard uncertainty; u above is that of the lines other than "
              "the table's (the budget's u_c with the table line at MPE/√3 per position does "
              "not hold the corner table and is kept in results.json, not stated)",
        "zh": "不给出 E 的合成标准不确定度：转台以其误差界 b 计入 U，而非以标准不确定度计入；"
              "上述 u 为转台以外各分量的合成（按每个位置最大允许误差/√3 计转台分量的预算 u_c 对角点转台"
              "不成立，仅记于 results.json，不作声明）"},
    "U_line_one_budget": {"en": "Uncertainty of each point's E_i (the draft's one Annex A budget, "
                                "the same at every point): U = {U}″, k = {k}, coverage "
                                "probability {p}",
                          "zh": "各测量点 E_i 的测量不确定度（按规范草案附录A的同一评定，各点相同）："
                                "U = {U}″，k = {k}，包含概率{p}"},
    "E_by_interval": {
        "en": "E = ± max|E_i| is stated by the 95 % coverage interval of the largest true |E_i|, "
              "[{lo}, {hi}]″: [max(0, max_i(|E_i| − c_L u_i − b_i)), max_i(|E_i| + c_H u_i + "
              "b_i)] from each point's E_i, u_i and b_i, the bound of the table's error at the "
              "point (MPE·Σ|c_p| over the point, the zero and the 7.1 stops; 0 where the table "
              "is calibrated or under the draft's one budget), which holds for every pattern of "
              "the true E_i and every table within its MPE (beyond the draft). The draft's reading as measured (none of the corrections beyond the draft), "
              "max|E_i| ± U (7.4, Annex A): {E} ± {U}″ (k = {k}), given beside and not "
              "certified.",
        "zh": "E = ± max|E_i| 以最大真值 |E_i| 的 95 % 包含区间 [{lo}, {hi}]″ 表述："
              "[max(0, max(|E_i| − c_L u_i − b_i)), max(|E_i| + c_H u_i + b_i)]（对各点取最大），"
              "由各点 E_i、u_i 及 b_i 求得，b_i 为该点转台误差的界（该点、零位及 7.1 各停止位置的"
              "最大允许误差乘 Σ|c_p|；转台经校准或按草案同一评定时为 0），对真值 E_i 的任何分布形态及"
              "最大允许误差以内的任何转台均成立（草案以外）。按规范草案的理解（测得值，未作草案以外的"
              "修正）max|E_i| ± U（7.4，附录A）：{E} ± {U}″（k = {k}），仅供参考，不作为校准结果。"},
    "k_fixed": {"en": "k: fixed by laboratory", "zh": "k：由实验室规定"},
    "k_welch": {"en": "k: t-factor of the effective degrees of freedom (Welch–Satterthwaite)",
                "zh": "k：按有效自由度（韦尔奇–萨特思韦特公式）取 t 分布因子"},
    "k_combined": {"en": "{items}: k is the 95 % half-width of the distribution the budget's "
                         "lines combine to (their convolution, computed numerically, JCGM 101 5.4) over u_c, "
                         "not t95(ν_eff): lines that are not normal carry more than a quarter of "
                         "u_c² (in brackets: the largest of them).",
                   "zh": "{items}：k 为其不确定度各分量合成分布（各分量分布的卷积，按 JCGM 101 "
                         "5.4 数值计算）的 95 % 半宽除以 u_c，不取 t95(ν_eff)：非正态分量占 u_c² "
                         "的四分之一以上（括号内为其中最大者）。"},
    "largest_line": {"en": " ({symbol}, {dist})", "zh": "（{symbol}，{dist}）"},
    "dist_arcsine": {"en": "arcsine", "zh": "反正弦分布"},
    "dist_rectangular": {"en": "rectangular", "zh": "均匀分布"},
    "dist_triangular": {"en": "triangular", "zh": "三角分布"},
    "dist_trapezoidal": {"en": "trapezoidal", "zh": "梯形分布"},
    "dist_rectangular-product": {"en": "product of two rectangulars", "zh": "两均匀分布之积"},
    "dist_rectangular-shifted-product": {"en": "product of two rectangulars",
                                         "zh": "两均匀分布之积"},
    "U_certified_physical": {
        "en": "Each point's U above is that of this calibration's physical budget (the draft's "
              "Annex A lines and the lines marked \"beyond the draft\", budget below). The "
              "draft's Annex A budget alone (its U is in the table of the readings beside the "
              "results, not certified) leaves out the tilt × Earth-rate coupling and the errors "
              "of the 7.1 K, which conditions the draft allows contain.",
        "zh": "上述各点的 U 按本次校准的物理模型评定（附录A各分量及标“超出草案”的分量，见下方不确定度"
              "分量表）。仅按规范草案附录A的评定（其 U 见结果旁列的读数表，不作为校准结果）未计入倾斜"
              "与地球自转角速度的耦合及 7.1 标度因数的误差，而草案允许的条件下这些影响存在。"},
    "U_certified_draft": {
        "en": "The U above is that of the draft's Annex A budget as the draft states it; the "
              "lines beyond the draft are not applied.",
        "zh": "上述 U 按规范草案附录A评定（草案的理解），未计入超出草案的分量。"},
    "beside_title": {
        "en": "The draft's readings and the notes on the results, given beside and not certified",
        "zh": "草案的读数及结果的说明（并列给出，不作为校准结果）"},
    "beside_reading": {"en": "Reading or note (not certified)", "zh": "读数或说明（不作为校准结果）"},
    "beside_E_draft": {
        "en": "the draft's reading as measured (none of the corrections beyond the draft), "
              "max|E_i| ± U (7.4, Annex A budget alone): {E} ± {U}″ (k = {k})",
        "zh": "按规范草案的测得值（未作草案以外的修正）max|E_i| ± U（7.4，仅按附录A评定）："
              "{E} ± {U}″（k = {k}）"},
    "beside_U_draft": {
        "en": "U of the draft's Annex A budget alone: {U}″ (k = {k})",
        "zh": "仅按规范草案附录A评定的 U：{U}″（k = {k}）"},
    "E_dcc_standard_mu": {
        "en": "The interval's si:valueStandardMU is the standard uncertainty of max|E_i| by the "
              "law of propagation at the estimates (JCGM 100 5.1.2): u_c of E_i at {p}°, the "
              "point where |E_i| is largest (results.json uncertainty.u_c, u_c_of). It holds to "
              "first order only, where that point's |E_i| stands clear of the others; the "
              "interval, which holds for every pattern of the true E_i, is the statement, not "
              "± k·u.",
        "zh": "该区间所附的标准不确定度为 max|E_i| 在估计值处按传播律（JCGM 100 5.1.2）求得的标准"
              "不确定度，即 |E_i| 最大的测量点（{p}°）的 E_i 的合成标准不确定度 u_c。它仅在该点的 "
              "|E_i| 明显大于其余各点时一阶成立；对真值 E_i 任何分布形态均成立的区间才是校准结果，"
              "不以 ± k·u 表述。"},
    "E_dcc_no_standard_mu": {
        "en": "No standard uncertainty of E is certified and the DCC states none "
              "(no si:valueStandardMU): each point's U = k·u + b carries the table by its bound "
              "b, not by a standard uncertainty; the interval's ends, the largest U's k, u of "
              "the lines other than the table's and b are in results.json "
              "(extra.uncertainty).",
        "zh": "不给出 E 的标准不确定度，数字校准证书亦不给出：各点 U = k·u + b 以误差界 b 计入"
              "转台，而非以标准不确定度计入；区间端点、最大 U 的 k、转台以外各分量的 u 及 b 见 "
              "results.json。"},
    "E_dcc_standard_mu_draft": {
        "en": "The interval's si:valueStandardMU is the standard uncertainty of max|E_i| by the "
              "law of propagation at the estimates (JCGM 100 5.1.2): u_c of the draft's one "
              "Annex A budget, the same at every point, so also at {p}°, where |E_i| is largest "
              "(results.json uncertainty.u_c, u_c_of). It holds to first order only, where that "
              "point's |E_i| stands clear of the others; the interval, which holds for every "
              "pattern of the true E_i, is the statement, not ± k·u.",
        "zh": "该区间所附的标准不确定度为 max|E_i| 在估计值处按传播律（JCGM 100 5.1.2）求得的标准"
              "不确定度，即规范草案附录A同一评定的合成标准不确定度 u_c（各点相同，|E_i| 最大的测量点 "
              "{p}° 亦然）。它仅在该点的 |E_i| 明显大于其余各点时一阶成立；对真值 E_i 任何分布形态"
              "均成立的区间才是校准结果，不以 ± k·u 表述。"},
    "U_certified_draft_interval": {
        "en": "Budget: the draft's Annex A budget as the draft states it, one for every point; "
              "the lines beyond the draft are not applied. Certified for E: the interval above, "
              "from this budget's u_c and ν_eff at every point. The draft's max|E_i| ± U takes "
              "U, a statement about one point, for the extreme of the points; it is given "
              "beside and not certified.",
        "zh": "不确定度按规范草案附录A评定，各点采用同一评定，未计入超出草案的分量。E 的校准结果为上述"
              "区间，由该评定的 u_c 与 ν_eff 对各点求得。草案的 max|E_i| ± U 将针对单点的 U 用于"
              "各点的极值，仅供参考，不作为校准结果。"},
    "budget_kind_draft": {"en": "Budget as the draft's Annex A states it.",
                          "zh": "按规范草案附录A的不确定度评定。"},
    "budget_kind_physical": {"en": "Budget of this calibration's physical model; lines marked "
                                   "\"beyond the draft\" are not in Annex A.",
                             "zh": "按本次校准的物理模型评定；标“超出草案”的分量不在附录A中。"},
    "no_E_U": {"en": "Angle-position deviation not measured: no uncertainty stated.",
               "zh": "未测角位置偏差：不给出测量不确定度。"},
    "m_spec": {"en": "Specification and clauses followed", "zh": "校准依据及所用条款"},
    "m_clauses": {"en": "clauses {c} (items measured)", "zh": "第 {c} 条（已测项目）"},
    "m_rates": {"en": "Table rates", "zh": "转台速率"},
    "m_rounds": {"en": "Rounds and series", "zh": "测回与组数"},
    "m_rounds_v": {"en": "7.1: {sf} rounds; 7.4: {ad} rounds × {s} series (7.5 from the same "
                         "series); 7.3: {zn} readings {zi} s apart",
                   "zh": "7.1：{sf} 个测回；7.4：{ad} 个测回 × {s} 组（7.5 用同一数据）；"
                         "7.3：{zn} 个读数，间隔 {zi} s"},
    "m_delay": {"en": "Reading", "zh": "读数"},
    "m_delay_v": {"en": "read {d} s after arrival; time from start to reading ≤ {t} s "
                        "(Annex A.1)",
                  "zh": "到位后 {d} s 读数；自起动至读数 ≤ {t} s（附录A.1）"},
    "m_earth": {"en": "Earth-rate compensation", "zh": "地速补偿"},
    "m_earth_measured": {"en": "measured: static phase of {s} s before each series",
                         "zh": "实测：每组前静态测量 {s} s"},
    "m_earth_computed": {"en": "computed from the latitude and the axis direction",
                         "zh": "由纬度和轴向计算"},
    "m_earth_none": {"en": "none", "zh": "无"},
    "m_latitude": {"en": "Site latitude", "zh": "测量地点纬度"},
    "m_axes": {"en": "Axis orientations", "zh": "轴向"},
    "m_tilt": {"en": "Tilt of the sensing plane", "zh": "敏感平面倾斜"},
    "m_tilt_v": {"en": "bound ψ ≤ {t}° (Annex A.4.2)", "zh": "上限 ψ ≤ {t}°（附录A.4.2）"},
    "m_tilt_measured": {"en": "measured in situ at {n} rest positions (Earth rate, beyond the "
                              "draft); the scale factor K is corrected for it",
                        "zh": "在 {n} 个静止位置上利用地球自转角速度现场实测（草案以外）；"
                              "标度因数 K 已按其修正"},
    "m_tilt_measured_e": {"en": "; so is every E_ij (7.4), its Annex A reading given beside",
                          "zh": "；各 E_ij（7.4）亦已修正，按附录 A 的测得值并列给出"},
    "m_temp": {"en": "Temperature", "zh": "温度"},
    "m_temp_v": {"en": "required ({t} ± {tol}) °C (Table 2); during calibration {m}",
                 "zh": "要求 ({t} ± {tol}) °C（表2）；校准时 {m}"},
    "m_readings": {"en": "Readings taken of the draft's ambiguities: see the section below.",
                   "zh": "对草案不明确之处的理解：见下节。"},
    "c_no_U": {"en": "no statement: the item has no stated uncertainty",
               "zh": "不作声明：该项目无测量不确定度"},
    "c_not_measured": {"en": "no statement: not measured", "zh": "不作声明：未测"},
    "d_round": {"en": "round", "zh": "测回"},
    "d_theta": {"en": "θ_i (°)", "zh": "θ_i (°)"},
    "d_counts": {"en": "C_i (counts)", "zh": "C_i（脉冲数）"},
    "d_K": {"en": "K_i (counts/°)", "zh": "K_i（脉冲数/(°)）"},
    "lg_all_series": {"en": "range of all {n} series", "zh": "全部 {n} 组的范围"},
    "lg_all_rounds": {"en": "range of all {n} rounds", "zh": "全部 {n} 次的范围"},
    "d_listed": {"en": "{listed} of {rows} rows listed: those farthest from the median of "
                       "{column} (range {min} … {max}); every row is in tables/{name}_table.csv.",
                 "zh": "共 {rows} 行，列出 {listed} 行：{column} 偏离中位数最远者（范围 {min} … "
                       "{max}）；全部数据见 tables/{name}_table.csv。"},
    "d_position": {"en": "position (°)", "zh": "位置（°）"},
    "d_E": {"en": "E_i (″)", "zh": "E_i (″)"},
    "d_R": {"en": "R_i (″)", "zh": "R_i (″)"},
    "d_n": {"en": "series n", "zh": "组数 n"},
    "d_rate": {"en": "rate (°/s)", "zh": "速率（(°)/s）"},
    "d_axis": {"en": "axis direction", "zh": "轴向"},
    "d_role": {"en": "role", "zh": "作用"},
    "d_reference": {"en": "reference condition", "zh": "参考条件"},
    "d_compared": {"en": "compared", "zh": "比较条件"},
    "d_Ev": {"en": "E (″)", "zh": "E (″)"},
    "d_maxabs": {"en": "max |E_i| (″)", "zh": "max |E_i| (″)"},
    "d_contrib": {"en": "|c_i|·u_i (″)", "zh": "|c_i|·u_i (″)"},
    "draft_for_comment": {"en": "(draft for comment)", "zh": "（征求意见稿）"},
    # the texts of its DCC, translated beside the English in a zh DCC
    "dcc_round_angle": {"en": "round angle θ_i", "zh": "测回角 θ_i"},
    "dcc_B_s_series": {"en": "B_s per series", "zh": "各组 B_s"},
    "dcc_drift_series": {"en": "linear drift per series", "zh": "各组线性漂移"},
    "dcc_E": {"en": "E = ± max|E_i| (draft 7.4)", "zh": "E = ± max|E_i|（规范草案 7.4）"},
    "dcc_E_signed": {"en": "signed extreme of E_i", "zh": "E_i 的带符号极值"},
    "dcc_E_position": {"en": "position of the extreme", "zh": "极值所在位置"},
    "dcc_title": {"en": "Calibration of an optical-gyroscope angle measuring instrument",
                  "zh": "光学陀螺测角仪校准"},
}
