"""Chinese of the rate family's shared budget-source phrases (see gonio.report.i18n.phrase_zh)."""

#: Budget-source phrases both rate specifications' analyses use, in Chinese (each
#: specification's certificate data adds these to its own PHRASES_ZH).
_TB = (r"the gyro's temperature error at the set point: the chamber's deviation \(± bound\) "
       r"and the gyro's place in its volume \(± half the uniformity, JJF Table 2\), both "
       r"bounded and allowed at once, their bounds added linearly")
_TB_ZH = "设定点处陀螺的温度误差：温箱温度偏差（± 界限）与陀螺在温箱容积内的位置（± 均匀度之半，JJF 表2），二者均有界且可同时出现，界限线性相加"

COMMON_PHRASES_ZH = (
    (_TB, _TB_ZH),
    (_TB + r" × T_c,SF/a of 5\.1\.3\.4's runs \(0 without them\)",
     _TB_ZH + " × 5.1.3.4 各次试验的 T_c,SF/a（无该试验时为 0）"),
    (_TB + r" × the bias temperature coefficient of 5\.3\.3\.6's visits \(0 without them\)",
     _TB_ZH + " × 5.3.3.6 各次测量的零偏温度系数（无该测量时为 0）"),
    (_TB + r" × \(\|β\| \+ U\(β\)\) of 5\.3\.3\.6 \(0 without its visits\)",
     _TB_ZH + " × 5.3.3.6 的 (|β| + U(β))（无该测量时为 0）"),
    (r"the gyro's temperature error at the set points, any pattern within ± \(chamber "
     r"deviation bound \+ half the uniformity\) \(the errors may follow the set point: the "
     r"slope's bound \(δ \+ U/2\)·\|T_c\|·Σ\|T_i − T̄\|/Σ\(T_i − T̄\)²\)",
     "各设定点处陀螺的温度误差，±（温箱温度偏差界限 + 均匀度之半）内任意组合（误差可能随设定点变化：斜率界限 (δ + U/2)·|T_c|·Σ|T_i − T̄|/Σ(T_i − T̄)²）"),
    (r"chamber deviation at the set points, any pattern within ± bound \(the deviations may "
     r"be correlated: the slope's bound δ·\|T_c\|·Σ\|T_i − T̄\|/Σ\(T_i − T̄\)²\)",
     "各设定点的温箱温度偏差，± 界限内任意组合（各点偏差可能相关：斜率界限 δ·|T_c|·Σ|T_i − T̄|/Σ(T_i − T̄)²）"),
    (r"chamber's fluctuation \(± amplitude, period\) × the bias temperature coefficient, "
     r"through the band's Welch estimate \(one-sided: it adds power\)",
     "温箱温度波动（± 幅值、周期）× 零偏温度系数，经该频带的 Welch 谱估计（单侧：只增加功率）"),
    (r"sampling of a standard deviation of (\d+) values, s/√\(2ν\) \(GUM E\.4\.3\); U to "
     r"the one-sided χ² 95 % upper limit",
     "{1} 个值的标准偏差的抽样，s/√(2ν)（GUM E.4.3）；U 取至单侧 χ² 95 % 上限"),
    (r"acquisition gain on the whole output \(null included\)", "整个输出（含零点）上的采集增益"),
    (r"acquisition, relative", "数据采集（相对）"),
    (r"rate table, relative", "速率转台（相对）"),
    (r"(?:rate table|scale factor), relative(?: \(u1\))?: no certificate u stated; JJF 1535 "
     r"Table 2's 0\.05 % as a rectangular bound",
     "速率转台（相对）：未给出证书标准不确定度，按 JJF 1535 表2 的 0.05 % 作矩形分布界限"),
    (r"chamber deviation at T_BASE \(± bound\) × T_c,SF/a of 5\.1\.3\.4's runs "
     r"\(0 without them\)", "T_BASE 处温箱温度偏差（± 界限）× 5.1.3.4 各次试验的 T_c,SF/a（无该试验时为 0）"),
    (r"chamber deviation at T_BASE \(± bound\) × the bias temperature coefficient of "
     r"5\.3\.3\.6's visits \(0 without them\)",
     "T_BASE 处温箱温度偏差（± 界限）× 5.3.3.6 各次测量的零偏温度系数（无该测量时为 0）"),
    (r"the gyro's place in the chamber's volume \(± half its uniformity, JJF Table 2\) × "
     r"T_c,SF/a", "陀螺在温箱容积内的位置（± 均匀度之半，JJF 表2）× T_c,SF/a"),
    (r"the gyro's place in the chamber's volume \(± half its uniformity, JJF Table 2\) × "
     r"the bias temperature coefficient", "陀螺在温箱容积内的位置（± 均匀度之半，JJF 表2）× 零偏温度系数"),
    # the virtual rate bench both simulate on (protocols/benches/mems-adxrs610.toml), in the DCC
    (r"MEMS rate gyro \(virtual\)", "微机电速率陀螺（虚拟）"),
    (r"the two slopes' noise of the point means and bias drift",
     "两条斜率的各点均值噪声与零偏漂移"),
    (r"chamber fluctuation \(± amplitude, period\) × T_c,SF between the CW and CCW points",
     "顺时针与逆时针各点之间的温箱温度波动（± 幅值、周期）× T_c,SF"),
    (r"chamber fluctuation \(± amplitude, period\) × T_c,SF between the supply runs",
     "各电源电压测量之间的温箱温度波动（± 幅值、周期）× T_c,SF"),
    (r"input-axis alignment × horizontal Earth rate", "输入轴对准 × 地球自转角速度水平分量"),
    (r"scale factor, relative", "标度因数（相对）"),
    (r"spread over the power-ups", "各次上电之间的分散性"),
    (r"spread of the records", "各段记录的分散性"),
    (r"spread of the (\d+) records' times, s/√N", "{1} 段记录时间的分散性，s/√N"),
    # an item not measured for want of its test's records (each specification's items)
    (r"no '(\w+)' records in the readings", "读数中无 {1} 试验的记录"),
    (r"cross-axis coupling of the Earth rate \(bound\)", "地球自转角速度的交叉轴耦合（界限）"),
    (r"sampling of a standard deviation", "标准偏差的抽样"),
    (r"interpolation between grid points", "网格点间插值"),
    (r"interpolation \(linear vs quadratic in log f\)", "插值（对数频率下线性与二次之差）"),
    (r"between the result and the next step", "结果与下一步长之间"),
    (r"step between the candidate and the next tested value", "候选值与下一试验值之间的步长"),
    (r"spread of the 50 % rule's outcome under the data's noise \(its 95 % range is the "
     r"interval\)", "按本次数据噪声 50 % 判据结果的分散性（其 95 % 范围即为所给区间）"),
    (r"spread of the 50 % rule's outcome under the data's noise \(the interval: whole grid "
     r"steps holding at least 95 % of it\)",
     "按本次数据噪声 50 % 判据结果的分散性（所给区间：由整数个步长构成、包含其不少于 95 % 的范围）"),
    (r"95 % range of the 50 % rule's outcome under the data's noise",
     "数据噪声下 50 % 判据结果的 95 % 范围"),
    (r"smoothing step", "平滑步长"),
    (r"detection: where the stability crosses nominal.*relative sampling\s+deviation of a "
     r"window's stability", "判定：稳定性穿越 标称值·(1 ± z·r) 之处，r 为窗口稳定性的相对抽样偏差"),
    (r"noise of the smoothed output", "平滑后输出的噪声"),
    (r"five-term AVAR fit, u\(N\)", "五项 Allan 方差拟合，u(N)"),
    (r"five-term AVAR fit with band-limited flicker, u\(N\)",
     "五项 Allan 方差拟合（带限闪烁噪声），u(N)"),
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
    (r"bias drift over the turn projected on the regressor \(the slope's weights on the "
     r"records' windows under the walk and flicker of the static record\)",
     "转动期间零偏漂移在回归量上的投影（斜率对各段记录时间窗的权重，按静态记录的角速率随机游走与闪烁噪声）"),
    # the screening's findings (gonio.specs._rate_family.screening), on the certificate
    (r"(\w+) (\S+) departs from its neighbours by (\S+) \(limit (\S+)\)",
     "{1} 值 {2} 偏离相邻样本 {3}（限 {4}）"),
    (r"(\w+) (\S+) differs from the segment's (\S+)", "{1} 值 {2} 与该段的 {3} 不同"),
    (r"(\w+): (\w+) logged on 1 row in (\d+) \((\d+) of (\d+) rows\); each blank row takes the "
     r"value interpolated in time between the logged rows of its segment",
     "{1}：{2} 每 {3} 行记录一次（{5} 行中 {4} 行）；空白行取本段相邻记录值按时间线性插值"),
    (r"(\w+) (\S+) departs from the segment's (\S+) \(limit (\S+)\)",
     "{1} 值 {2} 偏离该段的 {3}（限 {4}）"),
    (r"time (\S+) s is (\S+) s off the segment's sampling grid \(step (\S+) s\)",
     "时间 {1} s 偏离该段采样网格 {2} s（步长 {3} s）"),
    (r"(\d+) sample\(s\) missing before time (\S+) s \(step (\S+) s\)",
     "时间 {2} s 之前缺少 {1} 个样本（步长 {3} s）"),
    (r"(\w+) run (\S+) \(all of it\) is missing from the readings",
     "{1} 第 {2} 次运行（全部）在读数中缺失"),
    (r"(\w+) run (\S+): the planned (\w+) = (.+) is missing from the readings",
     "{1} 第 {2} 次运行：计划的 {3} = {4} 在读数中缺失"),
    # the nominal-scale-factor-departs finding (gonio.specs._rate_family.screening)
    (r"nominal_scale_factor (\S+) departs from the scale factor the scale-factor test "
     r"measures, (\S+) \(ratio (\S+), beyond (\S+)× either way: a nominal in another "
     r"unit\?\); no item reads it \(every item uses the measured K\)",
     "元数据标称标度因数 nominal_scale_factor = {1} 与标度因数试验测得的 {2} 不符，比值 {3}，"
     "超出任一方向 {4} 倍（标称值单位有误？）；无校准项目使用该值（各项目均用实测 K）"),
    (r"the laboratory's assumption taken from JJF 1535 Table 2 \(IEC 62047-20 states no "
     r"requirement on the rate table's accuracy\)",
     "实验室依 JJF 1535 表2 所作的假定（IEC 62047-20 对转台准确度无要求）"),
    (r"JJF 1535 Table 2's rate accuracy \(the table is taken to conform to it\)",
     "JJF 1535 表2 的速率准确度（认定转台符合该要求）"),
    (r"the rate table's uncertainty is not stated \(no # rate_table_u_rel\): budgeted as a "
     r"table within ±(\S+) % of the set rate, (.+?): the items stated by the bound condition "
     r"add the table at ±(\S+) % linearly \(U = a \+ k·u\), the others budget it as a "
     r"rectangular line \(u = (\S+) relative\); a table outside it makes the stated U too "
     r"small — state rate_table_u_rel from the table's calibration certificate",
     "未给出速率转台的不确定度（无 # rate_table_u_rel）：按转台误差在设定速率的 ±{1} % 以内计入"
     "（{2}）：以界限条件表述的项目将转台误差按 ±{3} % 线性相加（U = a + k·u），其余项目按矩形分布"
     "计入（相对 u = {4}）；转台超出此界限时所给 U 偏小——请按转台校准证书给出 rate_table_u_rel"),
)
