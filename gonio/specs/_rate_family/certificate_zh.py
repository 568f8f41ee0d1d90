"""Chinese of the rate family's shared budget-source phrases (see gonio.report.i18n.phrase_zh)."""

#: Budget-source phrases both rate specifications' analyses use, in Chinese (each
#: specification's certificate data adds these to its own PHRASES_ZH).
COMMON_PHRASES_ZH = (
    (r"acquisition gain on the whole output \(null included\)", "整个输出（含零点）上的采集增益"),
    (r"acquisition, relative", "数据采集（相对）"),
    (r"rate table, relative", "速率转台（相对）"),
    (r"scale factor, relative", "标度因数（相对）"),
    (r"spread over the power-ups", "各次上电之间的分散性"),
    (r"spread of the records", "各段记录的分散性"),
    (r"cross-axis coupling of the Earth rate \(bound\)", "地球自转角速度的交叉轴耦合（界限）"),
    (r"sampling of a standard deviation", "标准偏差的抽样"),
    (r"interpolation between grid points", "网格点间插值"),
    (r"interpolation \(linear vs quadratic in log f\)", "插值（对数频率下线性与二次之差）"),
    (r"between the result and the next step", "结果与下一步长之间"),
    (r"step between the candidate and the next tested value", "候选值与下一试验值之间的步长"),
    (r"95 % range of the 50 % rule's outcome under the data's noise",
     "数据噪声下 50 % 判据结果的 95 % 范围"),
    (r"smoothing step", "平滑步长"),
    (r"detection: where the stability crosses nominal.*relative sampling\s+deviation of a "
     r"window's stability", "判定：稳定性穿越 标称值·(1 ± z·r) 之处，r 为窗口稳定性的相对抽样偏差"),
    (r"noise of the smoothed output", "平滑后输出的噪声"),
    (r"five-term AVAR fit, u\(N\)", "五项 Allan 方差拟合，u(N)"),
    (r"chamber deviation \(independent per point\)", "温箱温度偏差（各点独立）"),
    (r"chamber temperature deviation \(Table 2\)", "温箱温度偏差（表2）"),
    (r"bias drift between the two positions \(Allan fit: RRW, BI\)",
     "两个位置之间的零偏漂移（Allan 拟合：RRW、BI）"),
    (r"bias drift between the two records \(Allan fit: RRW, BI\)",
     "两段记录之间的零偏漂移（Allan 拟合：RRW、BI）"),
    (r"bias drift between the two rest points \(Allan fit: RRW, BI\)",
     "两个静止点之间的零偏漂移（Allan 拟合：RRW、BI）"),
    (r"bias drift between the visits \(Allan fit: RRW, BI\)",
     "各次到达之间的零偏漂移（Allan 拟合：RRW、BI）"),
    (r"bias drift over the turn projected on the regressor, u_drift\(duration\)·√\(2/n\)",
     "转动期间零偏漂移在回归量上的投影，u_drift(时长)·√(2/n)"),
)
