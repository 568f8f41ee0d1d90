"""The triad-alignment certificate's own text, as data (English, Chinese); the rendering is
:mod:`gonio.specs.triad_alignment.certificate_pages` on the shared certificate
machinery."""

from gonio.result.statement import p_text
from gonio.specs.triad_alignment.analysis import COVERAGE

#: The coverage probability as every triad output states it (0.9545: "95.45"; the k are
#: Student's t for it, EA-4/02 Annex E), the same as results.json's and the DCC's 0.9545.
P_STATED = p_text(COVERAGE)

#: The thermal lag τ of the ramp analysis, by ``RampAnalysis.lag_case`` (English, Chinese):
#: a lag the ramps do not resolve is stated as not resolved with its bound, never as τ̂.
LAG_TEXT = {
    "fit": ("τ = {tau} s, 95 %: {lo}–{hi} s", "τ = {tau} s，95 %：{lo}–{hi} s"),
    "above": ("τ ≥ {lo} s (95 %)", "τ ≥ {lo} s（95 %）"),
    "bound": ("not resolved: τ ≤ {hi} s (95 %)", "未分辨：τ ≤ {hi} s（95 %）"),
    "open": ("not resolved by the ramps", "斜坡数据无法分辨"),
}


def lag_phrase(ramp: dict, lang: str, fmt=lambda v: f"{v:.0f}") -> str:
    """The lag of a ramp analysis (its JSON: ``lag_case``, ``tau_s``, ``tau_low_s``,
    ``tau_high_s``) in ``lang``; ``fmt`` renders a time in seconds."""
    case = ramp.get("lag_case", "fit")
    text = LAG_TEXT[case][1 if lang == "zh" else 0]
    vals = {k: fmt(ramp[f]) for k, f in (("tau", "tau_s"), ("lo", "tau_low_s"),
                                          ("hi", "tau_high_s"))
            if ramp.get(f) is not None and ramp[f] == ramp[f] and abs(ramp[f]) != float("inf")}
    return text.format(**vals)


#: label key → (English, Chinese)
TEXT = {
    "std_table": ("rate table with temperature chamber", "速率转台及温度试验箱"),
    "std_accuracy": ("rate: relative u {rate}; axis: ±{bound}° per orientation",
                     "速率：相对标准不确定度 {rate}；转轴：各方位 ±{bound}°"),
    "h_alignment": ("Alignment matrix", "对准矩阵"),
    "alignment_note": ("System matrix M ({unit} per °/s) and bias vector b ({unit}) of G = M ω + b, "
                       "from {n} dwells{robust}; one statement per cell, coverage probability "
                       "p = " + P_STATED + " %: M the bound-condition interval [value − U, value + U], "
                       "U = a + k·u (the rate table's errors at their bounds, a, plus k·u of the "
                       "fit; no coverage factor of the whole), b value ± U (k = …), U = k·u, k = "
                       "t(ν) of b's own budget (ν by Welch–Satterthwaite); a, u, ν and k of every "
                       "cell in the uncertainty table below.",
                       "系统矩阵 M（{unit}/(°/s)）与零偏向量 b（{unit}），模型 G = M ω + b，"
                       "由 {n} 个测量段{robust}求得；每格一个表述，包含概率 p = " + P_STATED + " %："
                       "M 为界限条件区间 [值 − U, 值 + U]，U = a + k·u（转台误差取其界限的 a 加拟合的 "
                       "k·u；整体无包含因子），b 为 值 ± U（k = …），U = k·u，k 按 b 自身预算"
                       "（ν 按 Welch–Satterthwaite 公式）取 t 分布因子；各格的 a、u、ν 与 k 见下方不确定度表。"),
    "robust": (" (robust fit, IRLS)", "（稳健拟合，IRLS）"),
    "gyro": ("gyro", "陀螺"),
    "k_nu": ("k (ν)", "k（ν）"),
    "sub_inverse": ("Alignment matrix M⁻¹ (°/s per {unit}): ω̂ = M⁻¹ (G − b)",
                    "对准矩阵 M⁻¹（°/s 每 {unit}）：ω̂ = M⁻¹ (G − b)"),
    "sub_cross": ("Cross-axis sensitivity (IEC 62047-20 5.2) and residual leakage after alignment",
                  "交叉轴灵敏度（IEC 62047-20 5.2）及对准后残余交叉耦合"),
    "cross_note": ("S_ij = M_ij/M_ii before alignment; after applying M⁻¹ the leakage "
                   "M̂⁻¹M − I is zero for the estimate, with its interval shown "
                   "(what the alignment leaves). Values as ratios (1), each its interval.",
                   "对准前 S_ij = M_ij/M_ii；施加 M⁻¹ 后残余耦合 M̂⁻¹M − I 对估计值为零，表中给出其"
                   "扩展不确定度（对准后残留的量）。数值为比值（1），各为其区间。"),
    "pair": ("gyro ← rate about", "陀螺 ← 输入角速度轴"),
    "S_col": ("S before [interval]", "对准前 S [区间]"),
    "L_col": ("leakage after [interval]", "对准后残余 [区间]"),
    "averaging": ("Averaging time from the Allan deviation: τ = {tau} s (noise limit "
                  "ω sin ψ_T / 10 = {lim} °/s at ω = {w} °/s, ψ_T = {psi}°); shortest dwell "
                  "{dwell} s — {ok}.",
                  "由 Allan 偏差确定的平均时间：τ = {tau} s（噪声限 ω sin ψ_T / 10 = {lim} °/s，"
                  "ω = {w} °/s，ψ_T = {psi}°）；最短测量段 {dwell} s — {ok}。"),
    "sufficient": ("sufficient", "满足"),
    "insufficient": ("NOT sufficient", "不满足"),
    "outliers": ("Down-weighted readings (robust fit): {list}", "稳健拟合降权的读数：{list}"),
    "h_unc": ("Uncertainty of M and b", "M 与 b 的不确定度"),
    "unc_note": ("Type A from the weighted least-squares residuals (JCGM 100 4.2), the dwell "
                 "noise in two parts: white, σ_w² from the scatter about each orientation's own "
                 "bias, and a bias offset per orientation and static dwell, σ_B²: cov = "
                 "σ_w²(XᵀWX)⁻¹ + σ_B²(PZ)(PZ)ᵀ, ν by Welch–Satterthwaite; Type B, the rate "
                 "table: its rate error (relative u {rate}) and its spin axis at each "
                 "orientation (each component within ±{bound}°), first order. Monte Carlo "
                 "(JCGM 101){mc}: in results.json only, not certified (it redraws the fit's "
                 "noise, not the table).",
                 "A 类评定，由加权最小二乘残差求得（JCGM 100 4.2），驻留噪声分两部分：白噪声 σ_w²"
                 "（各方位相对其自身零偏的离散）与每个方位及每个静态驻留的零偏偏移 σ_B²：cov = "
                 "σ_w²(XᵀWX)⁻¹ + σ_B²(PZ)(PZ)ᵀ，ν 按 Welch–Satterthwaite 公式；B 类评定为速率转台："
                 "其速率误差（相对标准不确定度 {rate}）及各方位下转轴方向（各分量在 ±{bound}° 内），"
                 "一阶传播。蒙特卡洛法（JCGM 101）{mc}：仅载于 results.json，非校准结果（仅重抽拟合噪声，"
                 "不含转台）。"),
    "mc_trials": (" ({n} trials)", "（{n} 次试验）"),
    "mc_none": (" (not run: --monte-carlo N)", "（未运行：--monte-carlo N）"),
    "a_col": ("a (table at its bounds)", "a（转台误差取界限）"),
    "u_col": ("u (fit; other lines)", "u（拟合及其他分量）"),
    "bound_tag": ("bound condition", "界限条件"),
    "interval_head": ("[interval]", "[区间]"),
    "bound_note": ("One statement per item. The items the rate table enters (M, S, L and "
                   "K(ϑ, U)) are stated by the bound-condition interval: the table's errors at "
                   "their bounds — rate error at {rate_bound} relative, its certificate's "
                   "expanded uncertainty, every axis component at ±{bound}° — in their worst "
                   "combination, a, plus k·u of the other lines: U = a + k·u, with probability "
                   "at least p = " + P_STATED + " % at every table error within the bounds; no "
                   "coverage factor of the whole. The other items (b, b(ϑ, U)) are value ± U, "
                   "U = k·u, each with its own k; ARW(ϑ), a dispersion, by its one-sided χ² "
                   "interval [0, upper] alone (p = " + P_STATED + " %, no k). Conformity is decided on these "
                   "statements.",
                   "每项一个表述。受速率转台影响的项（M、S、L 及 K(ϑ, U)）以界限条件区间表述：转台误差"
                   "取其界限——速率误差取相对 {rate_bound}，即其证书的扩展不确定度，各转轴分量取 "
                   "±{bound}°——按最不利组合线性合成为 a，加上其他分量的 k·u：U = a + k·u；在界限内任一"
                   "转台误差下包含概率不低于 p = " + P_STATED + " %；整体无包含因子。其余各项（b、b(ϑ, U)）"
                   "为 值 ± U，U = k·u，各有其 k；ARW(ϑ) 为离散度，仅以单侧 χ² 区间 [0, 上限] 表述"
                   "（p = " + P_STATED + " %，无 k）。符合性按这些表述判定。"),
    "nu": ("ν", "ν"),
    "arw_upper": ("upper bound", "上限"),
    "arw_budget": ("ARW: u_c of its budget (the dwells' χ², the lift correction, the order, "
                   "the temperature reading) and ν = ½(N/u_c)² of its χ²",
                   "ARW：其不确定度分量的 u_c（各段 χ²、抬升修正、阶次、温度读数）及其 χ² 的 "
                   "ν = ½(N/u_c)²"),
    "h_thermal": ("Temperature and supply model", "温度与电源电压模型"),
    "thermal_note": ("K(ϑ, U) and b(ϑ, U) as polynomials in ϑ = T − {tref} °C and U = V − {vref} V, "
                     "ARW(ϑ) in ϑ; orders chosen by {crit}; temperature: the gyro's {tsrc}; "
                     "thermal programme: {src}.",
                     "K(ϑ, U) 与 b(ϑ, U) 为 ϑ = T − {tref} °C 与 U = V − {vref} V 的多项式，ARW(ϑ) "
                     "为 ϑ 的多项式；阶次按 {crit} 选取；温度取自陀螺的 {tsrc}；温度试验数据：{src}。"),
    "sensor": ("internal temperature sensor", "内部温度传感器"),
    "chamber": ("chamber temperature", "温度箱温度"),
    "crit_bic": ("the Bayesian information criterion (BIC, smallest wins)",
                 "贝叶斯信息准则（BIC，取最小）"),
    "crit_aic": ("the Akaike information criterion (AIC, smallest wins)",
                 "赤池信息准则（AIC，取最小）"),
    "crit_ftest": ("a forward F-test at α = 0.05", "前向 F 检验（α = 0.05）"),
    "crit_fixed": ("the user (fixed)", "用户指定（固定）"),
    "sub_channel": ("gyro {ch}: ϑ {lo} … {hi} °C, U {ulo} … {uhi} V",
                    "陀螺 {ch}：ϑ {lo} … {hi} °C，U {ulo} … {uhi} V"),
    "model": ("model", "模型"),
    "order": ("order ϑ / U", "阶次 ϑ / U"),
    "term": ("term", "项"),
    "coef": ("coefficient", "系数"),
    "orders_line": ("{name}: order ϑ {nt}, U {nu} chosen by {crit}; runner-up ϑ {nt2}, U {nu2} "
                    "({crit} {d} larger).",
                    "{name}：按 {crit} 选定阶次 ϑ {nt}、U {nu}；次优 ϑ {nt2}、U {nu2}（{crit} 大 {d}）。"),
    "sub_points": ("Certified values at the programme's set points",
                   "在温度试验设定点的校准值"),
    "points_note": ("K(ϑ, U) and b(ϑ, U) of the gyro soaked at each chamber set point T and "
                    "supply V (ϑ: the reading of the gyro's sensor there, relative to {tref} °C, "
                    "at which the model is evaluated), ARW(ϑ) at each set point; one statement "
                    "per cell, coverage probability p = " + P_STATED + " %: K the bound-condition "
                    "interval (U = a + k·u, a = |K| × the rate error at its bound; k and ν of the "
                    "other lines in its column “k (ν)”), b value ± U with its own k = t(ν_eff) "
                    "and that ν_eff in brackets; ARW, a "
                    "dispersion, by its one-sided χ² upper bound alone, p = " + P_STATED + " % (ν from the "
                    "dwells' χ² under white rate noise, the order and the temperature reading, "
                    "ν = ½(N/u_c)²; corrected for half the bias instability's full-band lift, "
                    "the other half in u_c), no k. U includes the fit, the "
                    "model order (the spread of the candidate orders' values at the point) and "
                    "the temperature reading; the bias is {bias}. The polynomial coefficients "
                    "below are information, not certified values.",
                    "陀螺在各温度箱设定点 T 保温、电源电压为 V 时的 K(ϑ, U) 与 b(ϑ, U)（ϑ：该点陀螺温度"
                    "传感器读数相对 {tref} °C 的值，模型在该处求值），以及各设定点的 ARW(ϑ)；各格为"
                    "每格一个表述，包含概率 p = " + P_STATED + " %：K 为界限条件区间（U = a + k·u，a = |K| × 速率误差界限；"
                    "“k (ν)”列为其他分量的 k 及其 ν），b 为 值 ± U，其 k = t(ν_eff)，括号内为该 ν_eff；ARW 为离散度，仅以单侧 χ² 上限表述，"
                    "p = " + P_STATED + " %（ν 由白噪声下各段的 χ²、模型阶次及温度读数给出，ν = ½(N/u_c)²；按零偏不稳定性"
                    "全频带抬升的一半修正，另一半计入 u_c），无 k。U 含拟合、模型阶次（各候选阶次"
                    "在该点的值的分散）及温度读数分量；零偏为{bias}。下列多项式系数仅供参考，不是校准值。"),
    "bias_long-term": ("the long-term bias (with the bias-instability term over one day, as "
                       "b_i of the alignment)", "长期零偏（含一天时间范围内的零偏不稳定性分量，"
                                                "与对准的 b_i 相同）"),
    "bias_in-run": ("the in-run bias of this programme (no static record for the "
                    "bias-instability term)", "本次试验内的零偏（无静态记录，不含零偏不稳定性分量）"),
    "points_unit": ("{name} in {unit}:", "{name} 单位 {unit}："),
    "sub_coef": ("Polynomial coefficients (information, not certified; u standard uncertainty)",
                 "多项式系数（仅供参考，非校准值；u 为标准不确定度）"),
    "ramp": ("Ramps: the static-soak model leaves {rms} °/s rms on the ramp blocks; with a "
             "rate-of-temperature-change term γ·dϑ/dt (γ = {g} (°/s)/(°C/s)) {rmsg} °/s; with a "
             "first-order lag of the temperature ({lag}) {rmsl} °/s; hysteresis between "
             "rising and falling ramps at equal chamber temperature (the model's input, not "
             "the sensor's) {hys} °/s.",
             "温度斜坡：静态保温模型在斜坡段的残差均方根为 {rms} °/s；加入温度变化率项 γ·dϑ/dt"
             "（γ = {g} (°/s)/(°C/s)）后为 {rmsg} °/s；对温度施加一阶滞后（{lag}）后为 "
             "{rmsl} °/s；同一温箱温度（模型输入，而非传感器温度）下升降温斜坡之间的迟滞 {hys} °/s。"),
    "sub_comp": ("Compensation: residuals before and after", "补偿前后的残差"),
    "comp_note": ("The model applied to the calibration record itself: at the soak points the "
                  "residuals are the fit's; the ramp blocks were not used by the polynomial fit.",
                  "模型用于本次温度试验数据本身：保温点的残差即拟合残差；斜坡段未参与多项式拟合。"),
    "readings_taken": ("Readings taken of the sources", "对参考文献的理解"),
    "residual": ("residual (rms)", "残差（均方根）"),
    "before": ("before (constant k0, b0)", "补偿前（常数 k0、b0）"),
    "after": ("after (model)", "补偿后（模型）"),
    "r_bias": ("bias at the soak points (°/s)", "保温点零偏（°/s）"),
    "r_scale": ("scale factor at the soak points (ppm)", "保温点标度因数（ppm）"),
    "r_ramp": ("bias on the ramp blocks (°/s)", "斜坡段零偏（°/s）"),
    "fig_alignment": ("Cross-axis sensitivity before and residual leakage after alignment; Allan "
                      "deviation of the static record and the averaging time",
                      "对准前交叉轴灵敏度与对准后残余耦合；静态数据的 Allan 偏差及平均时间"),
    "fig_model": ("gyro {ch}: b(ϑ, U) and K(ϑ, U) with the fitted polynomials and 2u bands",
                  "陀螺 {ch}：b(ϑ, U) 与 K(ϑ, U) 及拟合多项式和 2u 带"),
    "fig_check": ("gyro {ch}: ramp blocks against the static-soak model; residuals before and "
                  "after compensation", "陀螺 {ch}：斜坡段与静态保温模型；补偿前后残差"),
}

#: The readings taken (results.json's English notes, in order) in Chinese.
READINGS_TAKEN_ZH = (
    "对准：对全部测量段（绕各轴的 ± 角速率及静态位置）一次拟合 G = M ω + b，各方位的地球自转角速度"
    "按转台扫过的角度精确平均；只有一对 ± 测量时退化为文章的差分公式。",
    "不确定度：由拟合残差作 A 类评定，k = t(ν)，包含概率 p = " + P_STATED + " %；受速率转台影响的项"
    "（M、S、L、K）以界限条件区间 值 ± (a + k·u) 表述：转台误差取其界限按最不利组合为 a，加上其他分量的 "
    "k·u；每项一个表述。这些项的 JCGM 100 U 及运行了试验时的蒙特卡洛法（JCGM 101）u 载于 "
    "results.json 的细节中，非校准结果。",
    "对准后残余耦合：M̂⁻¹M − I 对估计值本身为零；其不确定度即对准后残留的量。",
    "平均时间：取各陀螺静态数据 Allan 偏差均低于 ω sin ψ_T / 10 的最短倍频程 τ（文章式 30b）。",
    "温度模型：多项式阶次按所述准则选取而非固定；模型输入为陀螺内部温度传感器的读数"
    "（论文 §6.1）；校准值为各温度设定点与电源电压下的 K、b 及 ARW，阶次选择的影响计入 U，"
    "多项式系数仅供参考。",
    "各设定点的 ARW：为离散度（静态测量段的样本标准差），仅以单侧 χ² 区间 [0, N·√(ν/χ²_(1−p),ν)] 表述，"
    "p = " + P_STATED + " %（与各项相同），无 k：ν 由白噪声（角速率白噪声，各段 ν = n − 1）下各段的 χ² 经拟合传递，并计入模型阶次"
    "与温度读数分量，ν = ½(N/u_c)²；零偏不稳定性对各段方差的抬升（B̂ 取自静态数据 Allan 偏差的平底）"
    "按其全频带闪烁噪声值的一半修正，另一半计入 u_c。",
)

#: The matrices the DCC writes as lists (name, item keys row by row).
MATRICES = (
    ("system matrix M", (("M_xx", "M_xy", "M_xz"), ("M_yx", "M_yy", "M_yz"),
                         ("M_zx", "M_zy", "M_zz"))),
    ("bias b", (("b_x", "b_y", "b_z"),)),
    ("cross-axis sensitivity S", (("S_xy", "S_xz", "S_yx", "S_yz", "S_zx", "S_zy"),)),
    ("residual leakage after alignment L", (("L_xy", "L_xz", "L_yx", "L_yz", "L_zx", "L_zy"),)),
)
#: The documents the triad calibration follows (with their number and year), en and zh.
#: (The laboratory's own controlled procedure is its lab file's ``[certificate] procedure``.)
NORM = ("Gyro triad alignment (gonio method) with IEC 62047-20:2014 5.2 "
        "(cross-axis sensitivity) and JCGM 100:2008",
        "三轴陀螺组件对准（gonio 方法），交叉轴灵敏度按 IEC 62047-20:2014 5.2，"
        "不确定度按 JCGM 100:2008")

#: The readings taken in Chinese by their opening words (the DCC's zh beside the English).
READINGS_ZH = dict(zip(("Alignment:", "Uncertainties:", "Residual leakage after alignment:",
                        "Averaging time:", "Temperature model:", "ARW at the set points:"),
                       READINGS_TAKEN_ZH))

#: The items' and matrices' names in Chinese (gonio.report.i18n.phrase_zh), for the DCC.
PHRASES_ZH = (
    (r"system matrix (M(?:_\w+)?)", "系统矩阵 {1}"),
    (r"bias (b(?:_\w+)?)", "零偏 {1}"),
    (r"cross-axis sensitivity (S(?:_\w+ = M_\w+/M_\w+)?)", "交叉轴灵敏度 {1}"),
    (r"residual leakage after alignment (L(?:_\w+)?)(?: \(M̂⁻¹M − I\))?",
     "对准后残余交叉耦合 {1}（M̂⁻¹M − I）"),
    (r"averaging time from the Allan deviation", "由 Allan 偏差确定的平均时间"),
    (r"scale factor (K_\w+) at (\S+) °C, (\S+) V", "标度因数 {1}（{2} °C，{3} V）"),
    (r"bias (b_\w+) at (\S+) °C, (\S+) V", "零偏 {1}（{2} °C，{3} V）"),
    (r"angle random walk (ARW_\w+) at (\S+) °C", "角度随机游走 {1}（{2} °C）"),
    (r"MEMS gyro triad \(virtual\)", "微机电三轴陀螺组件（虚拟）"),
    (r"mems-triad", "微机电三轴陀螺组件虚拟台架（mems-triad）"),
    # the clauses of the sources (docs/alignment.md, docs/thermal-model.md)
    (r"§4 eq\. (\S+)", "文章 §4 式 {1}"),
    (r"§4 (M̂⁻¹M − I)", "文章 §4 {1}"),
    (r"thesis eq\. (\S+)", "论文式 {1}"),
    (r"triad screening", "三轴组件数据筛查"),
    # the screening's findings a certificate shows (gonio.specs.triad_alignment.screen)
    (r"alignment dwell about (\S+) at (\S+) °/s: gyro (\w)'s output moved (\S+) from the "
     r"static median, the opposite sign of the rate \(a sign-flipped rate_dps or up\?\)",
     "绕 {1} 的对准测量段（{2} °/s）：陀螺 {3} 的输出相对静态中位数变化 {4}，与角速率符号相反"
     "（rate_dps 或 up 的符号可能有误）"),
    (r"no static record: the biases b_i are the in-run bias over this record, without the "
     r"bias-instability term, and the averaging time is not measured",
     "无静态记录：零偏 b_i 为本次记录内的零偏，不含零偏不稳定性分量，平均时间未测"),
    (r"steps? (\S+) missing before (\w+) step (\d+): the results rest on the rows present",
     "{2} 第 {3} 步之前缺少第 {1} 步：结果仅基于现有各行"),
    (r"the readings have no static record \(rows test = static\)",
     "读数中没有静态记录（test = static 的行）"),
    (r"(\d+) static soak dwells of one sample \(lines ([\d, ]+)\): one sample gives no "
     r"standard deviation, so no angle random walk from them",
     "{1} 个单样本静态保温测量段（第 {2} 行）：单个样本无标准差，不能由其得出角度随机游走"),
    (r"(\d+) static soak dwells hold one sample \(n_samples = 1\): one sample gives no "
     r"standard deviation; ARW\(ϑ\) needs at least 3 dwells of 2 or more samples",
     "{1} 个静态保温测量段仅含一个样本（n_samples = 1）：单个样本无标准差；ARW(ϑ) 至少需要 "
     "3 个含 2 个及以上样本的测量段"),
)
