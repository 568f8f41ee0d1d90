"""IEC 62047-20 results page as data: the characteristics grouped as in its clause 5
(scale factor 5.1, cross-axis 5.2, bias 5.3, noise 5.4, frequency band 5.5, resolution
5.6)."""

from gonio.specs._rate_family.certificate_zh import COMMON_PHRASES_ZH


GROUPS = (
    (1, "Scale factor (5.1)", "标度因数（5.1）", ("scale_factor", "initial_sf_variation",
                                               "sf_temperature_coefficient", "ratiometric_error",
                                               "linearity", "sf_stability", "symmetry")),
    (2, "Cross-axis sensitivity (5.2)", "交叉轴灵敏度（5.2）", ("cross_axis",)),
    (3, "Bias (5.3)", "零偏（5.3）", ("bias", "initial_bias_variation", "bias_repeatability",
                                    "bias_drift_after_power_on", "bias_temperature_coefficient",
                                    "bias_ratiometric_error", "bias_hysteresis", "g_sensitivity",
                                    "startup_time")),
    (4, "Output noise (5.4)", "输出噪声（5.4）", ("inband_noise", "broadband_noise", "arw",
                                                "bias_instability")),
    (5, "Frequency band (5.5)", "频带（5.5）", ("frequency_band",)),
    (6, "Resolution (5.6)", "分辨率（5.6）", ("resolution",)),
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

def _p_value_text(p: float, level: float) -> str:
    """A test's p-value as a sentence states it beside its level: 2 significant digits, and
    where those would contradict the decision the sentence states (p < level printed as a
    number not below it: 0.0496 as "0.05 < 0.05"), as many more (at most 6) as show it,
    rounded toward the side the decision is on (down below the level, up at or above it) —
    the rule :func:`gonio.result.statement.p_text` follows for a coverage probability: the
    printed digits never say what the number does not.

    >>> _p_value_text(0.0496, 0.05), _p_value_text(0.63, 0.05), _p_value_text(0.04999, 0.05)
    ('0.0496', '0.63', '0.0499')
    >>> _p_value_text(0.05, 0.05), _p_value_text(0.0012345, 0.05), _p_value_text(0.0499999999, 0.05)
    ('0.050', '0.0012', '0.0499')
    >>> _p_value_text(0.1004, 0.05)          # two significant digits, the trailing zero kept
    '0.10'
    """
    from decimal import ROUND_CEILING, ROUND_FLOOR, Decimal

    below = p < level
    text = f"{p:#.2g}"
    for digits in range(2, 8):
        if (float(text) < level) == below:
            return text
        d = Decimal(repr(p))
        q = Decimal(1).scaleb(d.adjusted() - digits)
        text = str(d.quantize(q, rounding=ROUND_FLOOR if below else ROUND_CEILING))
    return text


def _power_on_fit(details: dict, lang: str) -> str | None:
    """5.3.3.5's pooling decision as the certificate, summary.txt and the DCC state it, from
    the item's details (:func:`gonio.specs.iec62047_20.items.power_on_fit_decision`); None
    for a result stored before they held it."""
    basis = details.get("transient_basis")
    if basis is None:
        return None
    n, lvl = details.get("power_on_records"), details.get("transient_test_level")
    p = details.get("transient_test_p")
    pt = "—" if p is None else _p_value_text(p, lvl)
    en = {"one_record": "one record: its own transient fitted",
          "timing_differs": f"the {n} records differ in length or timing: one transient "
                            "fitted to each power-on",
          "not_refuted": f"one transient fitted to all {n} records: the likelihood-ratio "
                         f"test of one transient against one per record does not refute it "
                         f"(p-value {pt} ≥ {lvl:g})",
          "refuted": f"one transient fitted to each of the {n} power-ons: the likelihood-"
                     f"ratio test refutes one transient for all records (p-value {pt} < {lvl:g})"}
    zh = {"one_record": "仅一次记录：按其自身瞬态拟合",
          "timing_differs": f"{n} 次记录的长度或时间不同：每次上电各拟合一个瞬态",
          "not_refuted": f"{n} 次记录共同拟合一个瞬态：单一瞬态对各记录单独瞬态的似然比检验"
                         f"未予否定（p 值 {pt} ≥ {lvl:g}）",
          "refuted": f"{n} 次上电各拟合一个瞬态：似然比检验否定了所有记录共用一个瞬态"
                     f"（p 值 {pt} < {lvl:g}）"}
    if lang == "zh":
        return f"上电后零偏漂移（5.3.3.5）的选择超出量与区间：{zh[basis]}。"
    return (f"Bias drift after power on (5.3.3.5), its selection excess and interval: "
            f"{en[basis]}.")


#: What decided how an item was evaluated, stated under the results table, in summary.txt
#: and as the item's dcc:description (:func:`gonio.report.rate_content.item_conditions`).
ITEM_CONDITIONS = {"bias_drift_after_power_on": _power_on_fit}

HEADING = ("MEMS gyroscope calibration results (IEC 62047-20 test methods)",
           "MEMS陀螺仪校准结果（按 IEC 62047-20 试验方法）")

#: Where the rule to state U with each result comes from: IEC 62047-20 is a test method and
#: has none; the certificate follows JJF 1535 clause 8 k) and says so.
U_CLAUSE = ("IEC 62047-20 sets no rule for it; stated as JJF 1535 clause 8 k) asks",
            "IEC 62047-20 未作规定，按 JJF 1535 第8章 k) 给出")

#: The readings taken (results.json's English notes) in Chinese, by the note's clause prefix.
READINGS_ZH = {
    "5.1.3.1:": "5.1.3.1：静止点作为拟合点（2n + 1 个点），与 JJF 1535 不同。",
    "5.1.3.4:": "5.1.3.4：温度系数报告为 100·T_c,SF/a_BASE，单位 %/°C；斜率一并给出。",
    "5.1.3.5:": "5.1.3.5：R = [a_V − a_BASE·V/V_BASE]/a_BASE（比值 V/V_BASE，理想比例式陀螺为零）。",
    "5.1.3.6:": "5.1.3.6：FullScale = 实测 y(CW 最大) − y(CCW 最大)；线性度 = max |L_i|。",
    "5.1.3.8:": "5.1.3.8：由不含静止点的正反转分别拟合，带符号 (a_CW − a_CCW)/a_TYP。",
    "5.2:": "5.2：ω = (Out − Out,rest)/SF（原文的 × SF 量纲有误）；整周转动；±ω 半差作为不受零偏影响的改进。",
    "5.3.3.1:": "5.3.3.1：原文地球自转分量的 sin 与 cos 互换（勘误）；按物理关系：轴向上 Ω_E sin λ，"
                "水平 Ω_E cos λ cos φ。",
    "5.3.3.4:": "5.3.3.4：零偏重复性取各段记录的半极差 (max − min)/2。",
    "5.3.3.6:": "5.3.3.6：对 基准 → 最高 → 基准 → 最低 → 基准 的每次到达作最小二乘斜率。",
    "5.4.5.2:": ("5.4.5.2：在局部斜率为 −½ ± 0.05 处（所取解读：标准未给容差）拟合斜率 −½ 的直线，在 1 h 处"
                 "读数；校准值：该规则用于拟合噪声模型的曲线，直线除以模型在该范围内的抬升（规则直接用于数据、未修正的读数并列给出）。"),
    "5.4.5.3:": "5.4.5.3：在不少于 10 个分组的 τ 上取底值，除以 √(2 ln 2/π)（标准的读数，与结果并列给出，不作校准结果）；所给值为"
                "该读数减去本记录拟合噪声模型下该规则的偏差（底值 τ 处的其他噪声项、对 τ 取最小），"
                "以该规则分布给出的 95 % 区间表述（两侧各 2.5 %；无 k）。",
    "5.5:": "5.5：频带取 −3 dB 频率与相位滞后 90° 频率中较低者，两者均给出。",
    "5.1.4.1 e)": "5.1.4.1 e) 式（18）：记录了设定电压时，比例式陀螺的输出按各次运行自身的设定电压折算，"
                  "y = y_RAW·V_set/V_actual。",
    "5.3.3.3:": "5.3.3.3：各供电运行的零偏取其静止输出（含零点）；R 以 % 表示，输出单位下的偏离（表4 的 V）见详细数据。",
    "5.3.3.7:": "5.3.3.7：自下方到达为“升”，自上方到达为“降”；迟滞 = max |B_up − B_down|（读数与结果并列给出，不作校准结果）；"
                "给出值为该读数减去最大值选择偏差的中点，区间为 [0, 单侧 95 % 上限]。",
    "5.1.3.7:": "5.1.3.7：标准的读数为各恒定角速率下总体标准偏差的最大值 max δ_i（与结果并列给出，不作校准结果）；所给值为最大真值 "
                "max σ_i 的估计：该读数减去取最大值的偏差（单值凸性偏差与竞争速率全部选择超出量之间的中点，"
                "按比例的 χ 分布），以 95 % 区间表述（上端为各记录按其自身 ν 的 χ² 上限的最大值，下端不高于选择超出量范围上最大分散值的 χ² 下限；无 k）。",
    "5.3.3.9:": "5.3.3.9：参考输出为记录最后五分之一的平均值；标准的读数（最后一次超出带宽的时间）与结果并列给出，不作校准结果；所给值为"
                "带外时间（超出带宽的平滑值个数 × 步长）减去瞬态趋于平缓处的滞后偏差 t''·方差/2（一阶瞬态；仅用于有越出带宽的记录，且不小于 0 s；始终在带内的记录记为 0 s）。",
    "5.3.3.8:": "5.3.3.8：a = g cos γ，输入轴向上时 γ = 0（式（28）的 sin γ 自水平起算）；各角度扣除地球自转"
                "角速度；等步长转一整周。",
    "5.4.5.1 c)": "5.4.5.1 c)：宽带噪声 = 单边谱密度在 band_hz … broadband_high_hz 上的均方根；20 dB/dec 的 "
                  "c/f 值 c (°/s^1.5) 见详细数据。",
    "5.6:": "5.6：滤波为一个台阶内采样的平均；Noise,RMS = 静态记录 T 秒平均值的标准偏差；分辨率 = "
            "max(Out,resolution, Noise,RMS)。",
    "Uncertainties are computed": "不确定度由本次校准数据评定（GUM，k = t95(ν_eff)）。",
}

#: Budget sources and reasons in Chinese (see gonio.report.i18n.phrase_zh).
PHRASES_ZH = COMMON_PHRASES_ZH + (
    # the budget line of a_BASE's relative u_c in an item divided by it (items._e_a), and the
    # rate table's line standing for it where a_BASE's u_c is not known
    (r"scale factor, relative: u_c\(a_BASE\)/a_BASE of 5\.1\.3\.1, with its ν_eff",
     "标度因数（相对）：5.1.3.1 的 u_c(a_BASE)/a_BASE，含其有效自由度 ν_eff"),
    # the bias's lines of a_BASE (items._e_a_rest, items._bias_budget) and of 5.3.3.6's bound
    (r"scale factor, relative: u_rest/a_BASE of 5\.1\.3\.1's lines other than its bounded "
     r"ones, with their ν_rest",
     "标度因数（相对）：5.1.3.1 有界分量以外各分量的 u_rest/a_BASE，含其自由度 ν_rest"),
    (r"scale factor, relative: a_BASE's bounded part a/a_BASE of 5\.1\.3\.1 \(0 where it "
     r"has none\)", "标度因数（相对）：5.1.3.1 中 a_BASE 的有界部分 a/a_BASE（无有界部分时为 0）"),
    (r"scale factor, relative: the rate table's line alone \(a_BASE's u_c not known\)",
     "标度因数（相对）：仅计速率转台分量（a_BASE 的 u_c 未知）"),
    (r"scale factor, relative: the rate table's line alone \(a_BASE's u_c not known\): no "
     r"certificate u stated; JJF 1535 Table 2's 0\.05 % as a rectangular bound",
     "标度因数（相对）：仅计速率转台分量（a_BASE 的 u_c 未知）：未给出证书标准不确定度，按 JJF 1535 "
     "表2 的 0.05 % 作矩形分布界限"),
    # the chamber-effect-unbounded finding (gonio.specs.iec62047_20.items.chamber_effect_finding)
    (r"the chamber's temperature effect on the scale factor is not bounded: the "
     r"scale-factor temperature coefficient of 5\.1\.3\.4 is not measured \((.+)\), so the "
     r"intervals of (.+?) are stated without a term for it \(the gyro's temperature error at "
     r"T_BASE, ± (\S+) °C: the chamber's deviation and its place in the volume; the "
     r"chamber's fluctuation between the points\), nor do the items divided by a_BASE "
     r"through its u — measure 5\.1\.3\.4 or state the coefficient's bound",
     "温箱温度对标度因数的影响未给出界限：5.1.3.4 的标度因数温度系数未测得（{1}），故 {2} 的区间"
     "未计入该影响的分量（陀螺在 T_BASE 处的温度误差 ± {3} °C：温箱偏差及其在容积内的位置；"
     "各点之间的温箱温度波动），除以 a_BASE 的各项经其不确定度亦不含该分量——"
     "请测量 5.1.3.4 或给出该系数的界限"),
    # the bias-temperature-unbounded finding (gonio.specs.iec62047_20.items.bias_temperature_finding)
    (r"the chamber's temperature effect on the bias is not bounded: the bias temperature "
     r"coefficient of 5\.3\.3\.6 is not measured \((.+)\), so the intervals of (.+?) are "
     r"stated without a term for it \(the gyro's temperature error at T_BASE, ± (\S+) °C: the "
     r"chamber's deviation and its place in the volume\) — measure 5\.3\.3\.6 or state the "
     r"coefficient's bound",
     "温箱温度对零偏的影响未给出界限：5.3.3.6 的零偏温度系数未测得（{1}），故 {2} 的区间未计入该影响的"
     "分量（陀螺在 T_BASE 处的温度误差 ± {3} °C：温箱偏差及其在容积内的位置）——请测量 5.3.3.6 "
     "或给出该系数的界限"),
    (r"the readings hold no 5\.3\.3\.6 visits", "读数中没有 5.3.3.6 的温度点"),
    # the noise-temperature finding (gonio.specs.iec62047_20.items.noise_temperature_finding)
    (r"the noise items (.+?) hold at the gyro's temperature during the static record "
     r"\((.+?), the readings' temperature_c, with the gyro within ± (\S+) °C of it: the "
     r"chamber's deviation and its place in the volume\), not at T_BASE: their intervals "
     r"carry no term for the noise's temperature dependence \(the readings hold no 5\.3\.3\.6 "
     r"visits at two temperatures, which give its coefficient\)",
     "噪声项 {1} 仅对静态记录期间陀螺的温度成立（{2}，读数中的 temperature_c，陀螺在其 ± {3} °C "
     "以内：温箱偏差及其在容积内的位置），而非 T_BASE：其区间未计入噪声随温度变化的分量"
     "（读数中没有两个温度以上的 5.3.3.6 温度点，无法得到该系数）"),
    (r"the gyro's temperature during the static record against T_BASE \(± the chamber's "
     r"deviation and place bounds, and the record's logged offset\) × the white level's "
     r"coefficient from the 5\.3\.3\.6 visits, √\(c² \+ u²\(c\)\)",
     "静态记录期间陀螺温度相对 T_BASE 的偏差（± 温箱偏差及位置界限，加记录的温度偏移）× 由 5.3.3.6 "
     "温度点得到的白噪声水平系数 √(c² + u²(c))"),
    (r"half range of (\d+) records; interval from the distribution of the range of normal "
     r"values \(Tippett\)", "{1} 次记录的半极差；区间按正态值极差的分布求得"),
    (r"alignment of the input axis to the plane perpendicular to the rotation axis \(table axis "
     r"and fixture\): sin\(half-width\)", "输入轴与转轴垂直面的对准（转台轴与夹具）：sin(半宽)"),
    (r"bias of 5\.3\.3\.1", "5.3.3.1 的零偏"),
    (r"falling visit at (\S+) °C", "{1} °C 处的降温到达"),
    (r"rising visit at (\S+) °C", "{1} °C 处的升温到达"),
    (r"least-squares slope, from the noise of the point means", "最小二乘斜率，由各点平均值的噪声求得"),
    (r"least-squares slope(?: \(parallel\)| \(residual scatter\))?", "最小二乘斜率"),
    (r"noise of the point means / FullScale", "各点平均值的噪声 / FullScale"),
    (r"noise of the rotating means", "转动平均值的噪声"),
    (r"bias of the floor rule, E\*\[B\*\] − B, removed \(other noise terms at the floor τ, "
     r"minimum over τ\)", "底值规则的偏差 E*[B*] − B，已扣除（底值 τ 处的其他噪声项、对 τ 取最小）"),
    (r"phase/gain noise of the bracketing points", "相邻点的相位/增益噪声"),
    (r"rest output at (\S+) V", "{1} V 时的静止输出"),
    (r"slope from the K_i standard errors", "由 K_i 标准误差得到的斜率"),
    (r"slope from the K_i's noise u\(a_i\)", "由 K_i 的噪声 u(a_i) 得到的斜率"),
    (r"slope standard errors of the two fits", "两次拟合斜率的标准误差"),
    (r"Welch estimate", "Welch 谱估计"),
    (r"Welch estimate: correlated Hann lines and overlapping segments",
     "Welch 谱估计：汉宁窗谱线相关、分段重叠"),
    (r"pooled noise of the point means through the line's residual / FullScale",
     "各点平均值的合并噪声经直线残差传递 / FullScale"),
    (r"bias drift between the points through the line's residual / FullScale \(static "
     r"record's noise fit\)", "各点之间的零偏漂移经直线残差传递 / FullScale（静态记录的噪声拟合）"),
    (r"chamber fluctuation \(± amplitude, period\) × T_c,SF through the line's residual / "
     r"FullScale", "温箱波动（± 幅值、周期）× T_c,SF 经直线残差传递 / FullScale"),
    (r"selection excess of the largest \|L_i\| \(midpoint ± c_m·σ/2 removed\)",
     "|L_i| 取最大者的选择超出量（已减去中点，± c_m·σ/2）"),
    (r"linear interpolation in ln f: h²/8·\|p''\| from the neighbouring point's second "
     r"difference", "ln f 中线性插值：h²/8·|p''|，p'' 由相邻点的二阶差分求得"),
    (r"Welch estimate over the broadband lines", "宽带谱线上的 Welch 谱估计"),
    (r"spread of the floor rule: standard deviation of (\d+) seeded draws under the five-term "
     r"fit \(correlated Allan variances\)",
     "底值规则的分散性：五项拟合模型下 {1} 次定种子抽样（Allan 方差相关）的标准偏差"),
    (r"bias correction of the −½ line under the fitted model with band-limited flicker "
     r"\(half the correction\)", "带限闪烁噪声拟合模型下 −½ 斜率直线的偏差修正（取修正量的一半）"),
    (r"lift correction's model: band-limited against the five-term fit's factor over the "
     r"same τ \(bound\)", "抬升修正的模型：同一 τ 区间上带限闪烁拟合与五项拟合的抬升因子之差（界限）"),
    (r"time outside the band: the count's spread and the reference's error \(noise, bias "
     r"drift\) through the local slope",
     "带外时间：计数的分散性及参考值误差（噪声、零偏漂移）经局部斜率传递"),
    (r"noise of the visits' bias means", "各次到达零偏平均值的噪声"),
    (r"bias drift over the session \(Allan fit: RRW, BI\), variogram form",
     "整个过程中的零偏漂移（Allan 拟合：RRW、BI），变差函数形式"),
    (r"chamber deviation at each set point \(rectangular, shared by its visits\)",
     "各设定点的温箱偏差（矩形分布，同一设定点的各次到达共用）"),
    (r"chamber's periodic fluctuation", "温箱的周期性波动"),
    (r"the gyro's place in the volume", "陀螺在温箱容积中的位置"),
    (r"selection excess of the largest \|R\| over the supplies \(midpoint ± c_m·σ/2 removed\)",
     "各供电下 |R| 取最大者的选择超出量（已减去中点，± c_m·σ/2）"),
    (r"least-squares slope \((\w+)\)", "最小二乘斜率（{1}）"),
    (r"χ² of the −½ line's Allan variances: edf of the line reading under the fitted "
     r"five-term model", "−½ 直线各 Allan 方差的 χ²：拟合的五项模型下直线读数的等效自由度"),
    (r"selection excess of the largest of the noisy differences over the temperatures "
     r"visited twice \(midpoint ± c_m·σ/2 removed\)",
     "两次到达的各温度上含噪差值取最大者的选择超出量（已减去中点，± c_m·σ/2）"),
    (r"selection excess of the largest of the noisy smoothed values \(midpoint ± c_m·σ/2 "
     r"removed\)", "含噪平滑值取最大者的选择超出量（已减去中点，± c_m·σ/2）"),
    (r"bias drift over the record \(Allan fit: RRW, BI\): the rms of its largest excursion, "
     r"√\(2G\)·u_drift\(record\)",
     "记录期间的零偏漂移（Allan 拟合：RRW、BI）：其最大偏移的均方根，√(2G)·u_drift(记录)"),
    (r"bias drift over the record \(Allan fit: RRW, BI\)", "记录期间的零偏漂移（Allan 拟合：RRW、BI）"),
    (r"largest \|Out\(t\) − Out,ave\| over the records; u: the estimate's spread in (\d+) seeded "
     r"replicates of the fitted records \(c \+ A·e\^\(−t/τ\), one transient for all records, "
     r"white noise σ_y, bias drift from the Allan fit\); ν: Welch–Satterthwaite over σ_y², K², "
     r"B² and the replicates' count",
     "各记录中 |Out(t) − 参考段平均输出| 的最大值；u：拟合记录（c + A·e^(−t/τ)，各记录共用一个暂态；"
     "白噪声 σ_y、由 Allan 拟合得到的零偏漂移）的 {1} 次定种子复现中该估计值的分散性；ν：由 σ_y²、"
     "K²、B² 及复现次数按 Welch–Satterthwaite 公式求得"),
    (r"largest \|Out\(t\) − Out,ave\| over the records; u: the estimate's spread in (\d+) seeded "
     r"replicates of the fitted records \(c \+ A·e\^\(−t/τ\), white noise σ_y, bias drift from "
     r"the Allan fit\); ν: Welch–Satterthwaite over σ_y², K², B² and the replicates' count",
     "各记录中 |Out(t) − 参考段平均输出| 的最大值；u：拟合记录（c + A·e^(−t/τ)、白噪声 σ_y、由 Allan "
     "拟合得到的零偏漂移）的 {1} 次定种子复现中该估计值的分散性；ν：由 σ_y²、K²、B² 及复现次数按 "
     "Welch–Satterthwaite 公式求得"),
    (r"selection excess of the largest smoothed value, E\*\[R\*\] − R̂, removed",
     "平滑值取最大者的选择超出量 E*[R*] − R̂（已减去）"),
    (r"residual bias of the corrected reading, E\*\[V\*\] − R̂, removed",
     "修正后读数的剩余偏差 E*[V*] − R̂（已减去）"),
    (r"sampling of the largest standard deviation \(scaled χ\)", "最大标准偏差的抽样（按比例的 χ 分布）"),
    (r"bias of the largest spread, E\[max δ_i\] − max σ_i, removed \(midpoint of Jensen's alone "
     r"… the contenders' full selection excess\)",
     "最大分散值的偏差 E[max δ_i] − max σ_i，已扣除（取仅有单值凸性偏差与竞争者全部选择超出量之间的中点）"),
    (r"late bias of the count where the transient flattens, t''·var\(level\)/2, removed "
     r"\(shape factor 0 … 2\)", "瞬态趋于平缓处计数的滞后偏差 t''·方差(电平)/2，已扣除（形状因子 0 … 2）"),
)

#: The forward/reverse figure (gonio.report.rate_figures.draw_cw_ccw): 5.1.3.8's symmetry
#: item holds a_CW and a_CCW; the outputs carry the null output b_BASE, taken off the points.
#: The items the rate figures draw, by their role (gonio.report.rate_figures).
FIGURE_ITEMS = {"bias_temperature": "bias_temperature_coefficient",
                "sf_temperature": "sf_temperature_coefficient", "allan": "bias_instability",
                "arw": "arw", "bias_instability": "bias_instability",
                "bandwidth": "frequency_band"}
CW_CCW = {"item": "symmetry", "cw": ("a_CW", None), "ccw": ("a_CCW", None),
          "null_output_off": True, "ylabel": "y_j − (K·Ω_j + b_BASE)", "title": "sym"}
