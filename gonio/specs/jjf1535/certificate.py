"""JJF 1535-2015 Annex B (Fig. B.1), "MEMS gyroscope calibration results", as data.

The inner page groups the fifteen items: 1 scale factor (five items), 2 bias (five),
3 threshold, 4 resolution, 5 warm-up time, 6 angle random walk, 7 bandwidth. Annex B
has no uncertainty line; clause 8 k) requires one, so the certificate shows U (k) beside
each result that has a budget. The rendering is :mod:`gonio.report.rate_certificate`.
"""

from gonio.specs._rate_family.certificate_zh import COMMON_PHRASES_ZH


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

#: The conditions that define an item's measurand, stated under the results table (English,
#: Chinese templates filled from the item's details): the warm-up time (7.2.9) depends on the
#: window W, the block P and the nominal stability the reading taken compares with.
ITEM_CONDITIONS = {
    "nonlinearity": (
        "Nonlinearity (7.2.2): eq (6) as printed, the mean of the Q largest residuals, reads "
        "{reading:#.3g}; the value certified is that reading less the midpoint of the noise's "
        "selection excess (the largest of noisy residuals reads high).",
        "非线性度（7.2.2）：按原文式（6），Q 次最大残差的平均值为 {reading:#.3g}；所给校准值为该值减去"
        "噪声选择超出量的中点（含噪残差的最大值偏大）。"),
    "bias_stability": (
        "Bias stability (7.2.10): eq (19) as printed, the mean of the Q records' standard "
        "deviations, reads {reading_eq19_dph:#.3g} °/h (a mean of standard deviations reads low); "
        "the value certified is their root mean square, whose square is unbiased for the block "
        "means' variance.",
        "零偏稳定性（7.2.10）：按原文式（19），Q 段记录标准偏差的平均值为 {reading_eq19_dph:#.3g} °/h"
        "（标准偏差的平均值偏小）；所给校准值为其均方根，其平方是分块均值方差的无偏估计。"),
    "threshold": (
        "Threshold (7.2.6): the value is the tested rate of the programme's grid ({grid_dps} "
        "°/s, means of {samples} samples referred to the rests around each point) at which "
        "the 50 % rule stops; its interval, whole grid steps around the value, holds at least "
        "95 % of the rule's outcome under the readings' own noise, and p states its own "
        "probability. Where the noise decides the rule, another grid or averaging is "
        "another measurand.",
        "阈值（7.2.6）：校准值为方案速率序列（{grid_dps} °/s，各点取 {samples} 个采样的平均值，"
        "以其前后静止输出为参考）中 50 % 判据终止时的试验速率；区间为按本次数据噪声 50 % 判据"
        "结果中包含校准值、由整数个序列步长构成且概率不小于 95 % 的范围，p 为该区间本身的概率。噪声决定判据时，速率序列或平均采样数不同即为不同的被测量。"),
    "resolution": (
        "Resolution (7.2.7): the value is the tested increment of the programme's grid "
        "({grid_dps} °/s, means of {samples} samples, the base rate re-measured before each "
        "increment) at which the 50 % rule stops; its interval, whole grid steps around the "
        "value, holds at least 95 % of the rule's outcome under the readings' own noise, and "
        "p states its own probability. Where the noise decides the rule, "
        "another grid or averaging is another measurand.",
        "分辨率（7.2.7）：校准值为方案增量序列（{grid_dps} °/s，各点取 {samples} 个采样的平均值，"
        "每个增量前重测基准速率）中 50 % 判据终止时的试验增量；区间为按本次数据噪声 50 % 判据"
        "结果中包含校准值、由整数个序列步长构成且概率不小于 95 % 的范围，p 为该区间本身的概率。噪声决定判据时，增量序列或平均采样数不同即为不同的被测量。"),
    "warmup_time": (
        "Warm-up time (7.2.9): the earliest time after power-on from which every window of "
        "W = {window_samples} samples ({window_s:g} s) has a stability of P-sample block means "
        "(P = {block_samples} samples, {block_s:g} s; eq (18)) of at most the nominal "
        "{nominal_stability_dph:g} °/h; the mean over {records} power-ups, window starts "
        "every P samples.",
        "准备时间（7.2.9）：自通电起，此后每个 W = {window_samples} 个采样（{window_s:g} s）的窗口内，"
        "P 个采样平均值（P = {block_samples} 个采样，{block_s:g} s；式（18））的稳定性均不超过标称值 "
        "{nominal_stability_dph:g} °/h 的最早时刻；取 {records} 次通电的平均值，窗口起点步长为 P 个采样。"),
    "angle_random_walk": (
        "Angle random walk (7.2.13): formula (25)'s five-term fit, whose bias instability is "
        "flat at every τ, reads {formula_25_arw_deg_sqrt_h:#.4g} °/√h; the value certified is N "
        "of the same fit with the bias instability band-limited below a fitted correlation time "
        "(T_lo = {flicker_band_t_lo_s:#.3g} s; 0: flat), as a gyro's fades at short τ.",
        "角度随机游走系数（7.2.13）：按式（25）的五项拟合（零偏不稳定性在各 τ 均为常数）为 "
        "{formula_25_arw_deg_sqrt_h:#.4g} °/√h；所给校准值为同一拟合中零偏不稳定性在拟合的最短相关时间"
        "（T_lo = {flicker_band_t_lo_s:#.3g} s；0 为常数）以下按带限衰减时的 N（陀螺的零偏不稳定性在短 τ 处减弱）。"),
}

#: Page title.
HEADING = ("MEMS gyroscope calibration results", "微机电(MEMS)陀螺仪校准结果")

#: The readings taken (results.json's English notes) in Chinese, by the note's clause prefix.
READINGS_ZH = {
    "7.2.1:": "7.2.1：K 取 Q 次最小二乘 K_m 的平均值；每次校准前后静止输出的平均值被扣除；静止点不作拟合点。",
    "7.2.2:": "7.2.2：式（6）的分母取拟合量程 K(Ω_max+ − Ω_max−)，Ω_max− 带符号；最大残差的噪声选择超出量"
              "按其中点扣除，式（6）的原值并列给出。",
    "7.2.10:": "7.2.10：B_s 取各段记录标准偏差的均方根（式（19）的标准偏差平均值偏小；并列给出）。",
    "7.2.3:": "7.2.3：K̄_m = (K+ + K−)/2，报告其绝对值。",
    "7.2.6/7.2.7:": "7.2.6/7.2.7：式（13）/（14）的关系按双侧理解，|…|/|F*| ≤ 50 %。",
    "7.2.8/7.2.12:": "7.2.8/7.2.12：扣除地球自转角速度在输入轴上的投影（规范未扣除；在北纬 40° 处，"
                     "真值 5 (°/h)/g 会读成 14.7 (°/h)/g）。",
    "7.2.9:": "7.2.9：准备时间取此后每个窗口均满足标称稳定性的最早时刻。",
    "7.2.13:": "7.2.13：式（22）–（24）按原文相邻一个采样求差，随 2/k² 下降；角度随机游走取自重叠 "
               "Allan 方差（IEEE 952），零偏不稳定性按带限闪烁噪声拟合（式（25）的常数项结果并列给出），"
               "原文统计量并列给出并注明。",
    "7.2.14:": "7.2.14：各 B_i 使用同一温度下校准的标度因数。",
    "7.2.15:": "7.2.15：0 dB 取最低试验频率；−3 dB 即幅值比 10^(−3/20)；按对数频率插值。",
    "Uncertainties are computed": "不确定度由本次校准数据评定（GUM，k = t95(ν_eff)）；附录 A 另行复现"
                                  "（见 gonio 的附录 A 预算命令）。",
}

#: Budget sources and reasons (the analyses' English phrases) in Chinese: (regular expression,
#: Chinese template with the groups as {1}, {2}…); see gonio.report.i18n.phrase_zh.
PHRASES_ZH = COMMON_PHRASES_ZH + (
    (r"sampling of B_s: effective ν of the records' correlated block means \(variogram: white, "
     r"flicker, random walk; flicker and random walk at their upper 95 % limits\)",
     "B_s 的抽样：各段记录相关分块均值的有效自由度 ν（变差图：白噪声、闪烁噪声、随机游走；"
     "闪烁噪声与随机游走取其 95 % 上限）"),
    (r"mean of K_m", "K_m 的平均值"),
    # the budget line of K̄'s relative u_c in an item computed with K (items._e_K)
    (r"scale factor, relative: u_c\(K\)/K̄ of 7\.2\.1, with its ν_eff",
     "标度因数（相对）：7.2.1 的 u_c(K)/K̄，含其有效自由度 ν_eff"),
    (r"rate table, relative(?: \(u1\))?", "速率转台（相对）"),
    (r"data acquisition, relative(?: \(u2\))?", "数据采集（相对）"),
    (r"repeatability of the mean of Q calibrations, s\(K_m\)/√Q", "Q 次校准平均值的重复性 s(K_m)/√Q"),
    (r"mean of K_n,m", "K_n,m 的平均值"),
    (r"noise of the largest residual \(rate-point means, leverage\) scaled to the residuals' "
     r"spread over the Q calibrations",
     "最大残差的噪声（各速率点平均值，杠杆值），按 Q 次校准残差的分散性放大"),
    (r"noise of the largest residual \(rate-point means, leverage\)",
     "最大残差的噪声（各速率点平均值，杠杆值）"),
    (r"selection excess of the largest of the noisy residuals \(midpoint ± c_m·σ/2 removed\)",
     "含噪残差取最大者的选择超出量（已减去中点，± c_m·σ/2）"),
    (r"noise of the rate-point means", "各速率点平均值的噪声"),
    (r"spread of K_n,m", "K_n,m 的分散性"),
    (r"spread of K_a,m", "K_a,m 的分散性"),
    (r"rate-point means' noise through K\+ and K−", "各速率点平均值的噪声（经 K+ 与 K−）"),
    (r"rate-table ripple ≤ (\S+)·\|Ω\| \(once per revolution, unknown phase\) through K\+ and K−",
     "速率转台每转一次的速率波动 ≤ {1}·|Ω|（相位未知），经 K+ 与 K−"),
    (r"rate-table ripple ≤ (\S+)·\|Ω\| \(once per revolution, unknown phase\) in the largest "
     r"residual", "速率转台每转一次的速率波动 ≤ {1}·|Ω|（相位未知），在最大残差中"),
    (r"K at (\S+) °C \(fit standard error\)", "{1} °C 时的 K（拟合标准误差）"),
    (r"K at (\S+) °C \(noise of its rate points' means\)", "{1} °C 时的 K（各速率点平均值的噪声）"),
    (r"K at room temperature (\S+) °C", "室温 {1} °C 时的 K"),
    (r"bias at (\S+) °C", "{1} °C 时的零偏"),
    (r"mean of the Q records \(type A\)", "Q 段记录的平均值（A类）"),
    (r"input-axis alignment × horizontal Earth rate", "输入轴对准 × 地球自转角速度水平分量"),
    (r"window start step P·t0", "窗口起点步长 P·t0"),
    (r"spread of B_s,m over the records", "各段记录 B_s,m 的分散性"),
    (r"\+axis up mean", "输入轴向上的平均值"), (r"−axis up mean", "输入轴向下的平均值"),
    (r"least-squares slope", "最小二乘斜率"),
    (r"noise of the bracketing gains \(weighted by the interpolation\) and of the 0 dB gain",
     "相邻增益点的噪声（按插值权重）及 0 dB 增益的噪声"),
    (r"linear interpolation in ln f: h²/8·\|p''\| from a second difference over points at "
     r"least h/2 apart", "ln f 中线性插值：h²/8·|p''|，由间距不小于 h/2 的点的二阶差分求得"),
    (r"noise of the bracketing gains", "相邻增益点的噪声"),
    # the equipment its virtual programme names (simulate.py's '# table:'), in the DCC
    (r"rate table, two-axis position table, angular vibration table, chamber \(virtual\)",
     "速率转台、双轴位置转台、角振动台、温箱（虚拟）"),
)

#: Where the specification asks for the uncertainty statement, (English, Chinese).
U_CLAUSE = ("JJF 1535-2015 clause 8 k)", "JJF 1535-2015 第8章 k)")

#: The forward/reverse figure (gonio.report.rate_figures.draw_cw_ccw): 7.2.3's asymmetry
#: item holds each direction's mean scale factor (first of the m series); the outputs are
#: plotted as F̄_j − K̄·Ω_j (the output zero is in the mean line).
#: The items the rate figures draw, by their role (gonio.report.rate_figures).
FIGURE_ITEMS = {"bias_temperature": "bias_temperature_sensitivity",
                "sf_temperature": "sf_temperature_sensitivity", "allan": "angle_random_walk",
                "arw": "angle_random_walk", "bandwidth": "bandwidth"}
CW_CCW = {"item": "asymmetry", "cw": ("K_pos_m", 0), "ccw": ("K_neg_m", 0),
          "null_output_off": False, "ylabel": "F̄_j − K̄·Ω_j", "title": "asym"}
