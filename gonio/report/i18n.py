"""Certificate labels in English and Chinese, the CJK font, and the ONE number-display rule.

Contents
========
=========================  ==========================================================
:data:`LABELS`             label key → {"en": ..., "zh": ...}: the labels every certificate shares
:func:`labels`             the label mapping of one language
:func:`cjk_font`           name of an installed CJK font for matplotlib (or GonioError)
:func:`round_half_up`      a number to a given decimal place, half up, as text
:func:`display_number`     a number to ``sig`` significant digits, half up, as text
:func:`display_uncertainty`  U to 2 significant digits (JCGM 100 7.2.6)
:func:`parse_display`      a displayed number back to a float (for checks)
=========================  ==========================================================

Every number the certificate shows (HTML, PDF and figure annotations) goes through
:func:`round_half_up`; the other display functions only choose its decimal place.
``results.json`` keeps full precision.
"""

from __future__ import annotations

import functools
import math
import re
from decimal import Decimal

from gonio.errors import GonioError
from gonio.result.statement import (decimals_at_U, decimals_for_sig, k_text, nu_text,  # noqa: F401
                                    p_relation, p_text, round_half_up, state, unit_text_in)
# (the one rule: gonio.result.statement)

#: Languages the certificate can be written in.
LANGUAGES: tuple[str, ...] = ("en", "zh")


LABELS: dict[str, dict[str, str]] = {
    "title": {"en": "Calibration Certificate", "zh": "校准证书"},
    "certificate_no": {"en": "Certificate No.", "zh": "证书编号"},
    "colon": {"en": ": ", "zh": "："},
    "paren": {"en": " ({x})", "zh": "（{x}）"},
    "semi": {"en": "; ", "zh": "；"},
    "comma": {"en": ", ", "zh": "，"},
    "page_of": {"en": "Page {x} of {y}", "zh": "第 {x} 页 共 {y} 页"},
    "virtual": {"en": "VIRTUAL BENCH EXAMPLE — NOT A CALIBRATION CERTIFICATE",
                "zh": "虚拟台架示例 — 非校准证书"},
    "virtual_short": {"en": "VIRTUAL BENCH EXAMPLE", "zh": "虚拟台架示例"},
    "laboratory": {"en": "Laboratory", "zh": "校准机构"},
    "address": {"en": "Address", "zh": "地址"},
    "accreditation": {"en": "Accreditation", "zh": "认可/授权"},
    "contact": {"en": "Contact", "zh": "联系方式"},
    "customer": {"en": "Customer", "zh": "委托方"},
    "customer_address": {"en": "Customer address", "zh": "委托方地址"},
    "instrument": {"en": "Instrument calibrated", "zh": "被校仪器"},
    "description": {"en": "Description", "zh": "名称"},
    "model": {"en": "Model", "zh": "型号"},
    "serial": {"en": "Serial number", "zh": "出厂编号"},
    "manufacturer": {"en": "Manufacturer", "zh": "制造厂"},
    "date_receipt": {"en": "Date of receipt", "zh": "接收日期"},
    "date_calibration": {"en": "Date of calibration", "zh": "校准日期"},
    "date_issue": {"en": "Date of issue", "zh": "签发日期"},
    "place": {"en": "Place of calibration", "zh": "校准地点"},
    "specification": {"en": "Specification followed", "zh": "校准依据"},
    "standards": {"en": "Standards used and their traceability", "zh": "校准所用计量标准及溯源性"},
    "std_name": {"en": "Standard", "zh": "标准器"},
    "std_id": {"en": "Identifier", "zh": "编号"},
    "std_spec": {"en": "Accuracy", "zh": "准确度"},
    "std_cert": {"en": "Certificate", "zh": "证书号"},
    "std_trace": {"en": "Traceable to", "zh": "溯源至"},
    "environment": {"en": "Environment during calibration", "zh": "校准环境条件"},
    "temperature": {"en": "Temperature", "zh": "温度"},
    "humidity": {"en": "Relative humidity", "zh": "相对湿度"},
    "from_readings": {"en": "taken from the readings' metadata", "zh": "取自读数文件的元数据"},
    "chamber_profile": {"en": "Temperature chamber points", "zh": "温度试验箱温度点"},
    "chamber_bound": {"en": " (deviation within ±{b} °C)", "zh": "（偏差不超过 ±{b} °C）"},
    "not_stated": {"en": "not stated", "zh": "未说明"},
    "no": {"en": "No.", "zh": "序号"},
    "item": {"en": "Item", "zh": "校准项目"},
    "clause": {"en": "Clause", "zh": "条款"},
    "result": {"en": "Result", "zh": "校准结果"},
    "unit": {"en": "Unit", "zh": "单位"},
    "not_measured": {"en": "not measured", "zh": "未测"},
    "uncertainty": {"en": "Measurement uncertainty", "zh": "测量不确定度"},
    "screening_h": {"en": "Screening of the readings", "zh": "读数筛查"},
    # beside a line of the first page an identity finding contradicts (gonio.report.header)
    "identity_flag": {"en": "[contradicted: see “Screening of the readings”]",
                      "zh": "［存在矛盾：见“读数筛查”］"},
    "more_findings": {"en": "… {n} more in results.json (findings)",
                      "zh": "……另有 {n} 条，见 results.json"},
    "screening_note": {"en": "Screening of the readings: {n} reading(s) set aside (not used; "
                             "listed in results.json with line and reason) and {m} finding(s) "
                             "flagged (the programme's completeness, the mounting, the "
                             "files' identity: listed below); the results above rest on the "
                             "remaining data.",
                       "zh": "读数筛查：{n} 个读数被剔除（未使用，行号与原因见 results.json），"
                             "{m} 项标记的提示（校准程序完整性、安装、文件标识：见下）；以上结果基于其余数据。"},
    "component": {"en": "Component", "zh": "分量"},
    "source": {"en": "Source", "zh": "来源"},
    "type": {"en": "Type", "zh": "类别"},
    "u_i": {"en": "u_i (″)", "zh": "u_i (″)"},
    # per-item budgets of the rate certificates: u_i in its input's unit, |c_i|·u_i in the item's
    "budget_items": {"en": "Uncertainty budget of each item (from this calibration's data)",
                     "zh": "各校准项目的不确定度分量（依据本次校准数据）"},
    "u_i_item": {"en": "u_i (input's unit)", "zh": "u_i（输入量单位）"},
    "readings_taken_std": {"en": "Readings taken of the specification's text",
                           "zh": "对规范条文的理解"},
    "details": {"en": "Details of the measurements", "zh": "测量详细数据"},
    "figures": {"en": "Figures", "zh": "图"},
    "signatory": {"en": "Signatures", "zh": "签字"},
    "calibrated_by": {"en": "Calibrated by", "zh": "校准员"},
    "checked_by": {"en": "Checked by", "zh": "核验员"},
    "approved_by": {"en": "Approved by", "zh": "批准人"},
    "amendment_asked_by": {"en": "Amendment asked for by", "zh": "修订申请人"},
    "seal": {"en": "Seal of the result (SHA-256)", "zh": "结果封印（SHA-256）"},
    "seal_value": {"en": "{short}… (the whole value is in the DCC; the laboratory's record "
                         "of this result is verified against it)",
                   "zh": "{short}…（完整值见数字校准证书；本机构的结果记录据此核验）"},
    "people_required": {"en": "People required", "zh": "所需人员"},
    "people_3": {"en": "3: calibration, review and approval each by a different person",
                 "zh": "3 人：校准、核验、批准各由不同人员完成"},
    "people_2": {"en": "2: the calibration by one person, its review and approval by another",
                 "zh": "2 人：校准由一人完成，核验与批准由另一人完成"},
    "people_2_amendment": {"en": "2: the calibration by one person, its review by another; "
                                 "this amendment asked for and made by one person, approved "
                                 "by another",
                           "zh": "2 人：校准由一人完成，核验由另一人完成；本修订由一人提出并完成，"
                                 "由另一人批准"},
    "amendment": {"en": "This certificate amends and replaces certificate {old}, which is "
                        "withdrawn. Reason for the amendment: {reason}",
                  "zh": "本证书修订并取代证书 {old}，原证书作废。修订原因：{reason}"},
    "amendment_title": {"en": "Amendment", "zh": "修订"},
    "draft_short": {"en": "DRAFT", "zh": "草稿"},
    "draft_title": {"en": "Draft — not a calibration certificate", "zh": "草稿 — 非校准证书"},
    "draft": {"en": "DRAFT FOR REVIEW — NOT AN ISSUED CERTIFICATE",
              "zh": "审核用草稿 — 非正式签发的证书"},
    "statement_item": {"en": "The results relate only to the item calibrated.",
                       "zh": "本证书的校准结果仅对所校准的仪器有效。"},
    "statement_copy": {"en": "This certificate shall not be reproduced except in full without "
                             "the written approval of the issuing laboratory.",
                       "zh": "未经本机构书面批准，不得部分复制本证书。"},
    "statement_recal_agreed": {"en": "Recalibration interval: {n} months, as agreed with the "
                                     "customer ({a}).",
                               "zh": "复校时间间隔：{n} 个月（与委托方约定：{a}）。"},
    "virtual_note": {"en": "Produced by gonio from a virtual bench (simulated readings). It "
                           "demonstrates the layout and the computations only; it certifies "
                           "nothing about any instrument.",
                     "zh": "本文件由 gonio 根据虚拟台架（模拟读数）生成，仅演示版式与计算，"
                           "不证明任何仪器的计量特性。"},
    "virtual_source": {"en": "The readings name the virtual bench {bench}, seed {seed}, in "
                             "their own metadata: every output says so, whatever the laboratory "
                             "file says.",
                       "zh": "读数文件的元数据表明其来自虚拟台架 {bench}（种子 {seed}）：无论实验室"
                             "文件如何填写，所有输出均如此标明。"},
    "virtual_evidence": {"en": "The readings' own metadata ({keys}) say they come from the "
                               "virtual bench: every output says so, whatever the laboratory "
                               "file says.",
                         "zh": "读数文件的元数据（{keys}）表明其来自虚拟台架：无论实验室文件如何"
                               "填写，所有输出均如此标明。"},
    "virtual_derived": {"en": "{files}, used with the readings, was computed from the virtual "
                              "bench's readings (its source says so): every output says so, "
                              "whatever the laboratory file says.",
                        "zh": "与读数一同使用的 {files} 由虚拟台架的读数计算得出（其来源如此记载）："
                              "无论实验室文件如何填写，所有输出均如此标明。"},
    "virtual_watermark": {"en": "The readings' own values carry the virtual bench's watermark "
                                "({cells} cells, chance on other readings {p}): every output "
                                "says so, whatever their header lines or the laboratory file "
                                "say.",
                          "zh": "读数数值本身带有虚拟台架的水印（{cells} 个数据，非台架读数偶然"
                                "吻合的概率 {p}）：无论文件头或实验室文件如何填写，所有输出均如此"
                                "标明。"},
    "source_file": {"en": "Readings file", "zh": "读数文件"},
    "truth": {"en": "virtual-bench truth (systematic part)", "zh": "虚拟台架真值（系统部分）"},
    # units as shown
    **{f"u_{u}": {lg: unit_text_in(u, lg) for lg in ("en", "zh")}
       for u in ("counts/deg", "%", "deg/h", "deg/s", "arcsec", "ppm")},
    # figures
    "lg_U": {"en": "U", "zh": "U"},
    "no_data": {"en": "not measured", "zh": "未测"},
    "up": {"en": "up", "zh": "竖直向上"}, "north": {"en": "north", "zh": "正北"},
    "south": {"en": "south", "zh": "正南"}, "east": {"en": "east", "zh": "正东"},
    "west": {"en": "west", "zh": "正西"},
    # the expanded uncertainty with its k and p (a DCC text of every specification)
    "U_cell": {"en": "{U} (k = {k}, p {r} {p} %)", "zh": "{U}（k = {k}，p {r} {p} %）"},
    # k = t_p(ν_eff): the ν it was computed from beside it (the one statement rule's ν)
    "U_cell_nu": {"en": "{U} (k = {k}, ν_eff = {nu}, p {r} {p} %)",
                  "zh": "{U}（k = {k}，ν_eff = {nu}，p {r} {p} %）"},
    # an item stated by its χ² interval: no U, no k; the ν that interval was computed with
    "U_cell_interval_nu": {"en": "— (ν_eff = {nu})", "zh": "—（ν_eff = {nu}）"},
    # where the coverage factor k comes from
    "k_each_item": {"en": "U: expanded uncertainty, k = t95(ν_eff) of each item's effective "
                          "degrees of freedom (shown per item in the budgets below); {clause}.",
                    "zh": "U：扩展不确定度，k = t95(ν_eff)，按各项的有效自由度取值（见下方各项"
                          "不确定度分量）；{clause}。"},
    # the legend of the items stated by an interval: one part per kind of interval present
    # (gonio.report.stated.interval_legend)
    "k_iv_head": {"en": "An item stated by an interval has that one statement, shown in the "
                        "result with its probability, and no U and no k: {kinds}.",
                  "zh": "以区间表述的项目只有这一个表述，在结果栏中连同包含概率给出，无 U，无 k：{kinds}。"},
    "k_iv_chi2": {"en": "a standard deviation (a repeatability, a stability, a noise rms) by "
                        "its one-sided 95 % upper limit (σ's χ² distribution with the ν_eff shown, "
                        "JCGM 100 E.4.3), on which any conformity decision is made",
                  "zh": "标准偏差（重复性、稳定性、噪声均方根）给出其单侧 95 % 上限（标准偏差按所示 "
                        "ν_eff 的 χ² 分布，JCGM 100 E.4.3），对上限的判定亦以此为据"},
    "k_iv_range": {"en": "a half range by its one-sided 95 % upper limit (the range of normal "
                         "values)",
                   "zh": "半极差给出其单侧 95 % 上限（按正态极差分布）"},
    "k_iv_belt": {"en": "a range corrected for its bias (a nonlinearity, a consistency) by the "
                        "95 % interval of its confidence belt (the measured range's distribution "
                        "under the budget's errors, JCGM 101)",
                  "zh": "修正偏差后的极差（非线性度、一致性）给出其置信带的 95 % 区间（在不确定度分量"
                        "误差下测得极差的分布，JCGM 101）"},
    "k_iv_max_abs": {"en": "the largest magnitude of several points, max_i |x_i|, by the 95 % "
                           "interval of that extreme, [max(0, max_i(|x_i| − c_L·u_i)), "
                           "max_i(|x_i| + c_H·u_i)] from each point's x_i and u_i, which holds "
                           "for every pattern of the points' true values (not max|x_i| ± k·u of "
                           "one point)",
                     "zh": "多个点的最大绝对值 max|x_i| 给出该极值的 95 % 区间 [max(0, max(|x_i| − "
                           "c_L·u_i)), max(|x_i| + c_H·u_i)]（对各点取最大，由各点的 x_i 与 u_i "
                           "求得），对各点真值的任何分布形态均成立（而非单点的 max|x_i| ± k·u）"},
    "k_iv_max_abs_bound": {"en": "the largest magnitude of several points into which bounded "
                                 "errors enter, by the same interval with each point's bounded "
                                 "errors at their bounds added to its reach, [max(0, "
                                 "max_i(|x_i| − c_L·u_i − b_i)), max_i(|x_i| + c_H·u_i + b_i)], "
                                 "u_i of the other lines (those errors named after its clause), "
                                 "which holds at every error within the bounds",
                           "zh": "受有界误差影响的多个点的最大绝对值给出同一区间，各点的有界误差取其界限加入其延伸："
                                 "[max(0, max(|x_i| − c_L·u_i − b_i)), max(|x_i| + c_H·u_i + "
                                 "b_i)]，u_i 为其他分量的（这些误差列于其条款之后），在界限内任一误差下成立"},
    "k_iv_sel_max": {"en": "the largest of several standard deviations, the selection bias of the "
                           "maximum removed (the midpoint of its bounds), by the 95 % interval "
                           "of the largest true spread that inverts each record's own χ² test: "
                           "its upper end the largest of the records' own χ² upper bounds, its "
                           "lower end the largest of their lower bounds at the Šidák level, for "
                           "any true spreads and record lengths",
                     "zh": "若干标准偏差中的最大者（扣除取最大值的选择偏差，取其界限的中点），由反演各记录"
                           "自身 χ² 检验所得最大真标准偏差的 95 % 区间给出：上端为各记录自身 χ² 上限中的"
                           "最大者，下端为各记录按多重比较（西达克）校正水平的下限中的最大者，对任何真标准偏差与记录长度"
                           "均成立"},
    "k_iv_bound": {"en": "a quantity bounded errors enter by its bound-condition interval "
                         "value ± (a + k·u): those errors (the item's bounded lines, named "
                         "after its clause; the table's where none are named) at their "
                         "bounds in their worst combination, added linearly, a, plus k·u of the other lines (ν stated is theirs), which "
                         "holds at every error within the bounds",
                   "zh": "受有界误差影响的量给出其界限条件区间 值 ± (a + k·u)：这些误差（该项的有界分量，列于"
                         "其条款之后；未列出者为转台误差）取其界限按最不利组合线性相加为 a，加上其他分量的 k·u"
                         "（所给 ν 为其他分量的），在界限内任一误差下成立"},
    "k_iv_bound_chi2": {"en": "a dispersion (a noise rms s) whose reading bounded errors scale, "
                              "by its one-sided bound-condition limit [0, (s + R)/(1 − g)] = "
                              "[0, s + a + R]: those errors (named after its clause) at their "
                              "bounds with the sign that lowers the reading, g, and R the reach "
                              "of the one-sided χ² 95 % limit of its other lines (ν stated is "
                              "theirs, ½(s/u_rest)²), which holds at every error within the "
                              "bounds",
                        "zh": "读数受有界误差按比例影响的离散量（噪声均方根 s）给出其单侧界限条件上限 "
                              "[0, (s + R)/(1 − g)] = [0, s + a + R]：这些误差（列于其条款之后）取其界限"
                              "并取使读数偏低的符号为 g，R 为其他分量单侧 χ² 95 % 上限的增量（所给 ν 为其他"
                              "分量的，½(s/u_rest)²），在界限内任一误差下成立"},
    # a bounded line of a bound-condition item, by its budget symbol (details.bound_condition
    # .a_lines); the rate table's where the item names none
    "bound_line_e_table": {"en": "the rate table's error", "zh": "转台误差"},
    "bound_line_e_TU": {"en": "the gyro's temperature error at the set point",
                        "zh": "陀螺在设定点的温度误差"},
    "bound_line_dT": {"en": "the gyro's temperature error at the chamber's set points",
                      "zh": "陀螺在温箱设定点的温度误差"},
    "bound_line_e_align": {"en": "the input axis's misalignment on the Earth rate",
                           "zh": "输入轴对准误差对地球自转角速度的影响"},
    "bound_line_e_a_bnd": {"en": "the scale factor's bounded part",
                           "zh": "标度因数的有界部分"},
    "bound_line_dT_noise": {"en": "the gyro's temperature during the static record × the noise's "
                                  "temperature coefficient",
                            "zh": "静态记录期间陀螺的温度误差 × 噪声的温度系数"},
    "k_iv_own": {"en": "an extreme or a rule's outcome by the 95 % interval of its own "
                       "distribution (Monte Carlo, a folded normal, a pivot)",
                 "zh": "极值或判定规则的结果给出其自身分布（蒙特卡洛、折叠正态、枢轴量）的 95 % 区间"},
    "k_iv_upper": {"en": "a quantity that cannot be negative whose U exceeds its value by its "
                         "upper bound, value + U (the interval value ± U without its impossible "
                         "negative part, JCGM 100 4.3.9)",
                   "zh": "不能为负且 U 大于其值的量给出其上限 值 + U（区间 值 ± U 去掉不可能的负值部分，"
                         "JCGM 100 4.3.9）"},
    "k_iv_clauses": {"en": " ({c})", "zh": "（{c}）"},
    "u_c_word": {"en": "combined standard uncertainty", "zh": "合成标准不确定度"},
    "u_c_beside_word": {"en": "combined standard uncertainty of the budget (the bounded lines as "
                              "rectangular distributions): beside, not stated — it does not hold "
                              "those errors at their bounds; the U row below is the statement",
                        "zh": "预算的合成标准不确定度（有界分量按矩形分布计）：仅列于旁，不作声明——"
                              "它对界限处的误差不成立；下行 U 为所作表述"},
    "src_own_A": {"en": "scatter of the item's own readings (Type A)",
                  "zh": "本项目读数的分散性（A类）"},
    "src_own_B": {"en": "bound from the specification's procedure (Type B)",
                  "zh": "按规范程序给出的界限（B类）"},
    # method
    "method": {"en": "Method", "zh": "校准方法"},
    # conformity
    "conformity": {"en": "Statement of conformity (ISO/IEC 17025 7.8.6)",
                   "zh": "符合性声明（ISO/IEC 17025 7.8.6）"},
    "rule_simple": {"en": "Decision rule: simple acceptance (ILAC-G8:09/2019 4.2.1, guard band "
                          "w = 0); the specific false-accept probability is stated under a "
                          "normal measurement model (JCGM 106), for a standard deviation "
                          "stated with its χ² interval under its χ² model.",
                    "zh": "判定规则：简单接受（ILAC-G8:09/2019 4.2.1，保护带 w = 0）；按正态测量模型"
                          "（JCGM 106）给出特定误接受概率，以 χ² 区间给出的标准偏差按其 χ² 模型。"},
    "rule_guarded": {"en": "Decision rule: binary statement with guarded acceptance, guard band "
                           "w = {r}·U (ILAC-G8:09/2019 4.2.2); the specific false-accept "
                           "probability is stated under a normal measurement model (JCGM 106), "
                           "for a standard deviation stated with its χ² interval under its χ² "
                           "model.",
                     "zh": "判定规则：带保护带的二元判定，保护带 w = {r}·U（ILAC-G8:09/2019 4.2.2）；"
                           "按正态测量模型（JCGM 106）给出特定误接受概率，以 χ² 区间给出的标准偏差"
                           "按其 χ² 模型。"},
    "rule_non-binary": {"en": "Decision rule: non-binary statement with guard band w = {r}·U "
                              "(ILAC-G8:09/2019 4.2.3): pass, conditional pass, conditional fail, "
                              "fail; the specific false-accept probability is stated under a "
                              "normal measurement model (JCGM 106), for a standard deviation "
                              "stated with its χ² interval under its χ² model.",
                        "zh": "判定规则：带保护带 w = {r}·U 的非二元判定（ILAC-G8:09/2019 4.2.3）："
                              "合格、有条件合格、有条件不合格、不合格；按正态测量模型（JCGM 106）"
                              "给出特定误接受概率，以 χ² 区间给出的标准偏差按其 χ² 模型。"},
    "rule_agreed": {"en": "Agreed: {a}", "zh": "约定：{a}"},
    "c_source_line": {"en": "Source of the specification limits: {s}.",
                      "zh": "规定限的来源：{s}。"},
    "c_source_unstated": {"en": "laboratory file (source not stated)",
                          "zh": "实验室文件（未注明出处）"},
    "list_sep": {"en": ", ", "zh": "、"},
    "end_mark": {"en": "End of certificate", "zh": "证书结束"},
    "fig_no": {"en": "Fig. {n}", "zh": "图{n}"},
    "unit_one": {"en": "(dimensionless)", "zh": "（量纲为一）"},
    "procedure": {"en": "Laboratory procedure", "zh": "实验室校准程序"},
    "c_limits": {"en": "Specification limits", "zh": "规定限"},
    "c_default": {"en": "(default of the specification)", "zh": "（规范默认值）"},
    "c_default_note": {"en": "Limits marked as the default of the specification are the "
                             "tolerances its document gives ({s}), used where the laboratory "
                             "file gives none.",
                       "zh": "标注为规范默认值的规定限取自规范文件给出的允差（{s}），"
                             "仅用于实验室文件未给出限值的项目。"},
    "c_accept": {"en": "Acceptance interval", "zh": "接受区间"},
    "c_outcome": {"en": "Outcome", "zh": "判定结果"},
    "c_pfa": {"en": "Specific false-accept probability", "zh": "特定误接受概率"},
    "c_pfr": {"en": "false-reject probability {v} %", "zh": "误拒绝概率 {v} %"},
    "c_pc": {"en": "Probability of conformance", "zh": "符合概率"},
    "c_acc_empty": {"en": "none (guard bands wider than the tolerance)",
                    "zh": "无（保护带宽于允差区间）"},
    "c_acc_iv_upper": {"en": "interval's upper end ≤ {hi}", "zh": "区间上端 ≤ {hi}"},
    "c_acc_iv_lower": {"en": "interval's lower end ≥ {lo}", "zh": "区间下端 ≥ {lo}"},
    "c_acc_iv_both": {"en": "interval within [{lo}, {hi}]", "zh": "区间 ⊆ [{lo}, {hi}]"},
    "c_no_p_note": {"en": "“—”: no probability is stated for {items}: its distribution is not one "
                          "gonio evaluates (a 95 % interval that is not that of a normal or "
                          "chi-square distribution, or a coverage factor k from a non-normal "
                          "combined distribution), and a normal N(y, u) would contradict it "
                          "(JCGM 106:2012 takes the measurand's own distribution); the outcome "
                          "is decided on the interval, or on y ± U, as stated.",
                    "zh": "“—”：{items} 不给出概率：其分布不是 gonio 所计算的分布（95 % 区间不是正态"
                          "分布或 χ² 分布的区间，或包含因子 k 来自非正态的合成分布），正态模型 N(y, u) "
                          "与之矛盾（JCGM 106:2012 取被测量自身的分布）；判定依据所给区间或 y ± U 作出。"},
    "c_measured_note": {"en": "Decided on the measurement result before rounding ({items}): "
                              "the value, against the acceptance interval its value and U "
                              "before rounding give, lies beyond the acceptance limit, where "
                              "the printed numbers, rounded to the digits stated, do not; the "
                              "stricter outcome is stated (ILAC-G8:09/2019 decides on the "
                              "measurement result).",
                        "zh": "按修约前的测量结果判定（{items}）：以修约前的值及其 U 所得的接受区间"
                              "衡量，该值超出接受限，而修约到所给位数的打印数值未超出；给出较严格"
                              "的结论（ILAC-G8:09/2019 依据测量结果判定）。"},
    "c_skewed_note": {"en": "{items}: a standard deviation decided on its estimate s as "
                            "printed (or on its interval), whose probability of conformance "
                            "lies on the other side of 50 % from its outcome: σ's χ² "
                            "distribution about s is skewed, its median above s, so s at or "
                            "just below a limit passes with p_c under 50 %; a guard band "
                            "(r ≥ 1) decides on the interval's upper end instead.",
                      "zh": "{items}：按所印估计值 s（或其区间）判定的标准差，其符合概率与判定结论"
                            "位于 50 % 的两侧：σ 关于 s 的 χ² 分布是偏斜的，其中位数高于 s，故 s "
                            "等于或略低于限值时判为合格而 p_c 低于 50 %；保护带（r ≥ 1）则按区间"
                            "上端判定。"},
    "c_guard_w": {"en": "Guard band w", "zh": "保护带 w"},
    "c_band_two": {"en": "{lo} at the lower limit, {hi} at the upper",
                   "zh": "下限处 {lo}，上限处 {hi}"},
    "c_measured_against": {"en": ", acceptance interval {acceptance}",
                           "zh": "，接受区间 {acceptance}"},
    "c_interval_band_note": {
        "en": "Guard band of an item stated by its {p} % interval alone ({items}): such an item "
              "is decided on its interval as printed, with w = r·δ, δ read off the printed "
              "ends: the interval's half-width, (upper end − lower end)/2 (the interval is its "
              "centre ± δ), or for a standard deviation stated by its one-sided χ² bound the "
              "bound's reach above the estimate, upper end − value (σ's χ² distribution about "
              "the estimate, whose probability of conformance is given). δ takes the place of "
              "U in w = r·U; it is not an expanded uncertainty of the item, and where a U is "
              "printed for the item δ can differ from it (even where the interval is the "
              "item's value ± U: its printed ends are rounded outward). "
              "w is applied to the interval's ends: each end is moved in by (r − 1)·δ, so at "
              "r = 1 the interval lies within the limits. An accepted item lies above its "
              "interval's upper end with a probability of at most 1 − p = {q} % (“≤ {q} %” "
              "where an item states it; a one-sided {p} % bound reaches that, an item stated y ± U with k "
              "for {p} % has at most {hq} % at r = 1).",
        "zh": "以 {p} % 区间单独表述的项目（{items}）的保护带：此类项目按所印区间判定，w = r·δ，"
              "δ 取自所印端点：区间的半宽，（上端 − 下端）/2（区间即 中点 ± δ）；以单侧 χ² 上限"
              "表述的标准差，δ 为上限高出估计值的量，上端 − 值（σ 关于估计值的 χ² 分布，并给出其"
              "符合概率）。δ 代替 w = r·U 中的 U，不是该项目的扩展不确定度；该项目另给出 U 时，"
              "δ 可能与之不同（区间即该项目的 值 ± U 时亦然：所印端点向外修约）。w 施加于区间的端点：两端各向内移 (r − 1)·δ，"
              "r = 1 时区间位于规定限之内。判为合格者其被测量高于区间上端的概率至多为 "
              "1 − p = {q} %（某项目给出“≤ {q} %”时即此；单侧 {p} % 上限可达此值，以 y ± U（{p} % 的 k）"
              "表述的项目在 r = 1 时至多 {hq} %）。"},
    "c_interval_band_item": {"en": "{name}: δ = ({hi} − {lo})/2 {unit} = {d} {unit}, w = {w} "
                                   "{unit}",
                             "zh": "{name}：δ = ({hi} − {lo})/2 {unit} = {d} {unit}，w = {w} "
                                   "{unit}"},
    "c_interval_band_item_chi2": {"en": "{name}: δ = {hi} − {v} {unit} = {d} {unit}, w = {w} "
                                        "{unit}",
                                  "zh": "{name}：δ = {hi} − {v} {unit} = {d} {unit}，w = {w} "
                                        "{unit}"},
    "c_no_statement": {"en": "no statement: {r}", "zh": "不作声明：{r}"},
    "pass": {"en": "pass", "zh": "合格"},
    "fail": {"en": "fail", "zh": "不合格"},
    "conditional pass": {"en": "conditional pass", "zh": "有条件合格"},
    "conditional fail": {"en": "conditional fail", "zh": "有条件不合格"},
    "rows_word": {"en": "{n} rows", "zh": "{n} 行"},
    "virtual_lab": {"en": "gonio virtual bench", "zh": "gonio 虚拟台架"},
    "virtual_place": {"en": "virtual bench", "zh": "虚拟台架"},
    "virtual_trace": {"en": "none (virtual bench)", "zh": "无（虚拟台架）"},
    "cjk_missing": {"en": "no CJK font installed: the specification's Chinese title is written in "
                          "English; install fonts-noto-cjk for the Chinese form",
                    "zh": "未安装中文字体"},
    "lg_u_bar": {"en": "error bars: standard uncertainty u", "zh": "误差棒：标准不确定度 u"},
}


_CLAUSE_REMARK = re.compile(r"^(\S+) \(([^()]+)\)$")


def clause_text(clause: str, L: dict) -> str:
    """A clause with its bracketed reference ("7.3 (3.3)": clause 7.3, definition 3.3) in the
    page's brackets (``L["paren"]``: full-width on a Chinese page).

    >>> clause_text("7.3 (3.3)", {"paren": "（{x}）"}), clause_text("7.1", {"paren": "（{x}）"})
    ('7.3（3.3）', '7.1')
    """
    m = _CLAUSE_REMARK.match(clause or "")
    return m.group(1) + L["paren"].format(x=m.group(2)) if m else clause


def labels(lang: str = "en", own: dict | None = None) -> dict[str, str]:
    """The labels of ``lang`` ("en" or "zh") as a flat mapping: the shared :data:`LABELS` and
    a specification's ``own`` ({key: {"en": …, "zh": …}}, its certificate's own labels; they
    take a shared key's place).

    >>> labels("zh")["not_measured"]
    '未测'
    >>> labels("zh", {"bias": {"en": "Bias B_0", "zh": "零偏 B_0"}})["bias"]
    '零偏 B_0'
    >>> labels("fr")
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: key lang: expected one of en, zh, got 'fr'
    """
    if lang not in LANGUAGES:
        raise GonioError(f"expected one of {', '.join(LANGUAGES)}, got {lang!r}", key="lang")
    return {k: v[lang] for k, v in (LABELS | (own or {})).items()} | {"_lang": lang}


#: Family names of CJK fonts looked for, best first.
CJK_FAMILIES: tuple[str, ...] = ("Noto Sans CJK SC", "Noto Sans CJK JP", "Noto Serif CJK SC",
                                 "Source Han Sans SC", "Source Han Sans CN", "WenQuanYi Zen Hei",
                                 "WenQuanYi Micro Hei", "AR PL UMing CN", "AR PL UKai CN",
                                 "Droid Sans Fallback", "Noto Sans SC", "SimHei",
                                 "Microsoft YaHei")
_CJK_FILE = re.compile(r"(cjk|wqy|wenquanyi|sourcehan|droidsansfallback|uming|ukai|simhei|msyh)",
                       re.IGNORECASE)


def cjk_font() -> str:
    """Family name of an installed CJK font matplotlib can use.

    Looks in matplotlib's font list, then scans the system font folders afresh
    (fonts installed after matplotlib built its cache). Raises a GonioError naming
    the package to install when there is none.
    """
    from matplotlib import font_manager as fm

    def known() -> str | None:
        names = {f.name for f in fm.fontManager.ttflist}
        return next((n for n in CJK_FAMILIES if n in names), None)

    name = known()
    if name is None:
        for path in fm.findSystemFonts():
            if _CJK_FILE.search(path):
                try:
                    fm.fontManager.addfont(path)
                except Exception:  # pragma: no cover - unreadable font file
                    continue
        name = known()
    if name is None:
        raise GonioError("--lang zh needs a CJK font and none is installed: install the "
                         "'fonts-noto-cjk' package (Debian/Ubuntu: apt-get install fonts-noto-cjk, "
                         "or run scripts/install-test-system-deps.sh)", key="lang")
    return name


# --------------------------------------------------------------------------- numbers

_SUP = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def display_number(x: float | None, sig: int = 3) -> str:
    """``x`` to ``sig`` significant digits, half up; below 10⁻³ as ``m×10⁻ⁿ``.

    A thin wrapper of the one statement rule (:func:`gonio.result.statement.state` without
    U); it adds only the text of a non-number (returned as written).

    >>> display_number(76434.8425925926, 8), display_number(2.0533102, 3)
    ('76434.843', '2.05')
    >>> display_number(2.1805064433995786e-05, 3), display_number(9.996e-05, 3)
    ('2.18×10⁻⁵', '1.00×10⁻⁴')
    >>> display_number(0.0, 3), display_number(None)
    ('0', '—')
    """
    try:
        x = None if x is None else float(x)
    except (TypeError, ValueError):
        return str(x)
    return state(x, sig=sig).value_text


def display_uncertainty(U: float) -> str:
    """Expanded uncertainty alone to 2 significant digits, half up (JCGM 100 7.2.6): the U
    part of :func:`gonio.result.statement.state`, without a common power of ten.

    >>> display_uncertainty(0.3589621064934065), display_uncertainty(0.297), display_uncertainty(0.0996)
    ('0.36', '0.30', '0.10')
    """
    return round_half_up(U, decimals_at_U(U))


#: U+2212 MINUS SIGN, the sign of a negative number as printed (ISO 80000-1 7.2 / SI Brochure
#: 5.4.1: the minus sign, not the hyphen).
MINUS = "\u2212"
#: An ASCII hyphen-minus that is a number's sign: before a digit (or ".5"), not after a Latin
#: letter, digit, point or dash (so "IEC 62047-20", "SN-0001" and "2026-11-29" keep theirs).
_SIGN = re.compile(r"(?<![0-9A-Za-z_.\-\u2212])-(?=\.?\d)")


def minus_sign(text: str) -> str:
    """``text`` as a certificate prints it: each negative number's sign as U+2212 MINUS SIGN
    (ISO 80000-1 7.2; SI Brochure 5.4.1), never the hyphen. Only what a certificate displays
    (HTML, PDF) goes through it: results.json, the DCC XML and summary.txt keep the ASCII
    hyphen-minus a program reads back.

    >>> minus_sign("-0.18″ at 270°; [-0.5, 0.5]; 10⁻⁵"), minus_sign("JJF 1535-2015, SN-0001")
    ('−0.18″ at 270°; [−0.5, 0.5]; 10⁻⁵', 'JJF 1535-2015, SN-0001')
    >>> minus_sign("（-3.0 s）"), minus_sign("bias-corrected"), minus_sign("-.5")
    ('（−3.0 s）', 'bias-corrected', '−.5')
    """
    return _SIGN.sub(MINUS, text)


_NUM = re.compile(r"^([+-]?\d+(?:\.\d+)?)(?:×10([⁻⁰¹²³⁴⁵⁶⁷⁸⁹]+))?$")
_UNSUP = str.maketrans("⁻⁰¹²³⁴⁵⁶⁷⁸⁹", "-0123456789")


def parse_display(text: str) -> float:
    """A displayed number back to a float (inverse of :func:`display_number`).

    >>> parse_display("2.18×10⁻⁵"), parse_display("+0.87"), parse_display("76434.843")
    (2.18e-05, 0.87, 76434.843)
    >>> parse_display("\u22120.12")       # a certificate's minus sign (minus_sign)
    -0.12
    """
    m = _NUM.match(text.strip().replace(MINUS, "-"))
    if not m:
        raise ValueError(f"not a displayed number: {text!r}")
    v = float(m.group(1))
    if m.group(2):
        v = float(Decimal(m.group(1)).scaleb(int(m.group(2).translate(_UNSUP))))
    return v


def last_digit_unit(text: str) -> float:
    """The unit of the last shown digit of a displayed number (half of it bounds the rounding).

    >>> last_digit_unit("0.36"), last_digit_unit("2.18×10⁻⁵"), last_digit_unit("1200")
    (0.01, 1e-07, 1.0)
    """
    m = _NUM.match(text.strip().replace(MINUS, "-"))
    if not m:
        raise ValueError(f"not a displayed number: {text!r}")
    mant = m.group(1)
    dec = len(mant.split(".")[1]) if "." in mant else 0
    e = int(m.group(2).translate(_UNSUP)) if m.group(2) else 0
    return float(Decimal(1).scaleb(e - dec))


def display_position(x: float) -> str:
    """A table position or other setting: half up to 3 decimals, trailing zeros dropped.

    >>> display_position(240.0), display_position(7.5), display_position(2.0)
    ('240', '7.5', '2')
    """
    s = round_half_up(x, 3)
    return s.rstrip("0").rstrip(".") if "." in s else s


def display(rule: str, value: float | None, U: float | None = None) -> str:
    """Every number of the certificate, by rule name — the single entry point.

    Rules: ``"U"`` (2 significant digits, :func:`display_uncertainty`),
    ``"dec<N>"`` (N decimal places; see :func:`rule_at_U`), ``"pmdec<N>"`` (± and the
    magnitude at N decimals: the draft's E = ± max|E_i|), ``"sdec<N>"`` (with its sign),
    ``"k"`` (a coverage factor: 3 significant digits, :func:`k_text`), ``"nu"``
    (ν_eff: its integer part, GUM G.6.4; ∞ above 1000), ``"nuchi2"`` (the ν of a χ²
    interval: its integer part, never ∞), ``"sci<E>.<N>"`` (the mantissa at N decimals ×
    10^E: a statement's common power of ten),
    ``"atU"`` (the decimal place of U), ``"sig<N>"`` (N significant digits),
    ``"pos"`` (:func:`display_position`), ``"int"`` (nearest integer).

    >>> display("U", 0.3589), display("atU", 0.0434, U=0.3589), display("sig3", 1296000.003)
    ('0.36', '0.04', '1296000')
    >>> display("int", 4586091.0)
    '4586091'
    """
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "—"
    value = float(value)
    if rule == "U":
        return display_uncertainty(value)
    if rule == "atU":
        if U is None or U <= 0:
            return display_number(value, 3)
        return round_half_up(value, decimals_for_sig(U, 2))
    if rule.startswith("sig"):
        return display_number(value, int(rule[3:]))
    if rule == "pos":
        return display_position(value)
    if rule == "int":
        return round_half_up(value, 0)
    if rule == "k":
        return k_text(value) or "—"
    if rule == "nu":
        return nu_text(value) or "—"
    if rule == "nuchi2":
        return nu_text(value, chi2=True) or "—"
    if rule.startswith("sci"):                  # "sci<E>.<N>": the mantissa at N decimals
        e, _, n = rule[3:].partition(".")       # × 10^E (a statement's common power of ten)
        e = int(e)
        m = float(Decimal(repr(value)).scaleb(-e))
        return f"{round_half_up(m, int(n or 1))}×10{str(e).translate(_SUP)}"
    for prefix, fmt in (("pmdec", "±{a}"), ("sdec", "{s}"), ("dec", "{v}")):
        if rule.startswith(prefix):
            dec = int(rule[len(prefix):])
            a = round_half_up(abs(value), dec)
            v = round_half_up(value, dec)
            s = v if v.startswith("-") or float(v) == 0 else "+" + v
            return fmt.format(a=a, s=s, v=v)
    raise ValueError(f"unknown display rule {rule!r}")


def rule_at_U(U: float | None, fallback_sig: int = 3, value: float | None = None,
              prefix: str = "dec") -> str:
    """The display rule of a value stated with its expanded uncertainty U (JCGM 100 7.2.6).

    U is given to two significant digits, the value to the same decimal place
    (rule ``dec<N>``); without U the value keeps ``fallback_sig`` significant digits
    (rule ``sig<N>``; the ± and signed forms then use the decimal place of those digits).

    >>> rule_at_U(0.3364), rule_at_U(0.0996), rule_at_U(12.4), rule_at_U(None)
    ('dec2', 'dec2', 'dec0', 'sig3')
    >>> rule_at_U(None, 3, -0.15228, "pmdec"), display("pmdec2", -0.15228), display("sdec2", 0.152)
    ('pmdec3', '±0.15', '+0.15')
    """
    if U is not None and math.isfinite(U) and U > 0:
        return f"{prefix}{decimals_for_sig(U, 2)}"
    if prefix != "dec" and value is not None and math.isfinite(value) and value != 0:
        return f"{prefix}{max(decimals_for_sig(value, fallback_sig), 0)}"
    return f"sig{fallback_sig}"


def coverage_text(p: float | None, lang: str = "en") -> str:
    """A coverage probability in words, p as :func:`~gonio.result.statement.p_text` states
    it (0.9545: "95.45", as results.json and the DCC carry it): a p chosen as such
    (:func:`~gonio.result.statement.p_relation` "=": 0.95, 0.9545) as it is, "95 %", any
    other "approximately 98 %" (JCGM 100 6.2.2), as "p ≈ 98 %" in the tables.

    >>> coverage_text(0.95), coverage_text(0.9545, "zh"), coverage_text(0.98), coverage_text(None)
    ('95 %', '95.45 %', 'approximately 98 %', '—')
    """
    if p is None:
        return "—"
    pct = p_text(p)
    if p_relation(pct) == "=":
        return pct + " %"
    return ("约 " if lang == "zh" else "approximately ") + pct + " %"


def phrase_zh(text: str, table=()) -> str | None:
    """The Chinese of an English phrase by a specification's table of (regular expression,
    Chinese template with the groups as {1}, {2}…), tried in order; None if none matches.

    >>> phrase_zh("K at 70 °C", [(r"K at (\\S+) °C", "{1} °C 时的 K")])
    '70 °C 时的 K'
    """
    for pat, zh in table:
        m = re.fullmatch(pat, text.strip())
        if m:
            return zh.format(None, *m.groups())
    return None


def source_text(src: str, L: dict, table=()) -> str:
    """A budget component's source in the certificate's language (by the specification's
    phrase ``table``, see :func:`phrase_zh`; a source no phrase knows stays as written).

    >>> source_text("zero drift (A.4.3)", labels("en"))
    'zero drift (A.4.3)'
    >>> source_text("zero drift", labels("zh"), [(r"zero drift", "零位漂移")])
    '零位漂移'
    """
    return (phrase_zh(src, table) or src) if L.get("_lang") == "zh" else src


def reason_text(reason: str, L: dict, table=(), extra: dict | None = None,
                own: dict | None = None) -> str:
    """Why an item was not measured, in the certificate's language: in Chinese through the
    specification's ``table`` and own labels and the shared ones (:func:`translator`); a
    reason no table knows stays as written."""
    if L.get("_lang") == "zh":
        return translator(extra, tuple(table), own)(reason) or reason
    return reason


# --------------------------------------------------------------------------- DCC texts (zh)

#: The fixed English texts of every DCC (gonio.report.dcc, rate_dcc, item_dcc) → Chinese,
#: written beside the English in a zh DCC (:func:`gonio.report.dcc.bilingual`).
DCC_ZH: dict[str, str] = {
    "serial number": "出厂编号",
    # the kinds of 95 % interval (results.json k_source) a "not given" probability names
    "interval of max|x_i| (uncertainty.extreme.max_abs_interval)": "多个点最大绝对值的区间",
    "interval of the largest true spread inverting each record's own χ² test":
        "由各记录自身 χ² 检验反演所得最大真标准偏差的区间",
    "χ² interval of the largest spread over its selection excess":
        "扣除选择偏差后最大标准偏差的 χ² 区间",
    "neyman-belt": "置信带",
    "normal range": "正态极差",
    "folded-normal maximum": "折叠正态最大值",
    "floor rule's distribution (pivot)": "下限规则的分布（枢轴量）",
    "replicates' distribution (pivot, 2.5 % each side, scaled by t95(ν_eff)/z95, ν_eff by "
    "Welch–Satterthwaite)":
        "重复样本的分布（枢轴量，两侧各 2.5 %，按 t95(ν_eff)/z95 放大，ν_eff 由 "
        "Welch–Satterthwaite 公式求得）",
    "outcome distribution": "结果分布",
    "its own": "其自身",
    "Reading taken of the specification's text": "对规范条文的理解",
    "Reading taken of the sources": "对参考文献的理解",
    "Uncertainty of measurement": "测量不确定度",
    "Each item's expanded uncertainty U = k·u_c is computed from the calibration's own data "
    "(JCGM 100), with k = t95(ν_eff) (Welch–Satterthwaite), coverage probability 95 %; the "
    "components are in results.json.":
        "各项目的扩展不确定度 U = k·u_c 由本次校准数据求得（JCGM 100），k = t95(ν_eff)"
        "（Welch–Satterthwaite 公式），包含概率 95 %；各分量见 results.json。",
    "Decision rule": "判定规则",
    "non-binary": "非二元判定",
    "guarded": "带保护带的二元判定",
    "simple": "简单接受",
    "lower specification limit": "规定下限",
    "upper specification limit": "规定上限",
    "probability of conformance": "符合概率",
    "specific false-accept probability": "特定误接受概率",
    "specific false-reject probability": "特定误拒绝概率",
    "room temperature": "室温",
    "temperature": "温度",
    "relative humidity": "相对湿度",
    "nominal supply voltage": "标称电源电压",
    "latitude of the site (Earth-rate components)": "所在地纬度（地球自转角速度分量）",
    "scale-factor input rates": "标度因数输入角速度",
    "chamber temperature points": "温箱温度点",
    "supply voltages": "电源电压",
    "angular vibration frequencies": "角振动频率",
    "traceable to none (virtual bench)": "无溯源（虚拟台架）",
    "none (virtual bench)": "无（虚拟台架）",
    "position": "位置",
    "axis direction": "轴向",
    "upper bound (coverage interval [0, upper bound]: a non-negative quantity whose U exceeds "
    "its value)": "上限（包含区间 [0, 上限]：非负量，U 大于其值）",
    "gonio virtual bench": "gonio 虚拟台架",
}

#: gonio.report.dcc.BOUND_INTERVAL as a regular expression (written out, so that a change of
#: the English fails the zh DCC test until its Chinese follows), and its Chinese.
_BOUND_INTERVAL_RE = (r"bound-condition interval, value ± \(a \+ k·u\): the bounded errors "
                      r"\(the table's where no certificate u is stated for it; the item's other "
                      r"bounded lines\) at their bounds in their worst combination, a, plus k·u "
                      r"of the other lines; no standard uncertainty of the item is certified")
_BOUND_INTERVAL_ZH = ("值 ± (a + k·u)：有界误差（未给出证书不确定度时的转台误差；该项的其他有界分量）"
                      "取其界限的最不利组合 a，加其他分量的 k·u；不给出该项的标准不确定度")
#: gonio.report.dcc.BOUND_CHI2_INTERVAL the same way, and its Chinese.
_BOUND_CHI2_INTERVAL_RE = (r"one-sided bound-condition limit, \[0, s \+ a \+ R\]: the bounded "
                           r"errors \(the item's bounded lines\) at their bounds with the sign "
                           r"that lowers the reading, a, plus the reach R of the one-sided "
                           r"chi-square limit of the other lines; no standard uncertainty of the "
                           r"item is certified")
_BOUND_CHI2_INTERVAL_ZH = ("[0, s + a + R]：有界误差（该项的有界分量）取其界限并取使读数偏低的符号为 a，"
                           "加其他分量单侧 χ² 上限的增量 R；不给出该项的标准不确定度")

#: gonio.report.dcc.MAX_ABS_BOUND_INTERVAL the same way, and its Chinese.
_MAX_ABS_BOUND_INTERVAL_RE = (r"the 95 % interval of the largest magnitude max\|x_i\|, each "
                              r"point's reach c·u_i \+ b_i: u_i of the lines other than the "
                              r"bounded ones, b_i their bound at the point; no standard "
                              r"uncertainty of the item is certified")
_MAX_ABS_BOUND_INTERVAL_ZH = ("最大绝对值 max|x_i| 的 95 % 区间，各点延伸 c·u_i + b_i：u_i 为有界分量以外各分量的合成，"
                              "b_i 为其在该点的界；不给出该项的标准不确定度")

#: DCC texts built from parts: (regular expression, Chinese template with the groups as {1},
#: {2}…; each group is itself translated where it can be, :func:`gonio.report.dcc.label_translator`).
DCC_PHRASES_ZH: tuple[tuple[str, str], ...] = (
    # the optical E's interval where each point's U = k·u + b (its DCC's E_BOUND_INTERVAL)
    (r"(.+): the coverage interval of the largest true \|E_i\|, each point's reach "
     r"k·u \+ b: u of the lines other than the table's, b the table's bound at the point; no "
     r"standard uncertainty of E is certified; p = (\S+) %",
     "{1}：最大真值 |E_i| 的包含区间，各点延伸 k·u + b：u 为转台以外各分量的合成，b 为该点"
     "转台误差的界；不给出 E 的标准不确定度；p = {2} %"),
    # a non-negative item whose estimate fell below zero, stated by its interval [0, upper]
    # alone (every DCC's BELOW_ZERO_INTERVAL, gonio.report.dcc)
    (r"(.+): stated by its upper bound alone, the interval \[0, upper bound\]: the "
     r"bias-corrected estimate fell below zero; no value is stated; p = (\S+) %",
     "{1}：仅以上限表述，区间 [0, 上限]：偏差修正后的估计值低于零；不给出量值；p = {2} %"),
    # a bound-condition interval's ends (gonio.report.dcc.BOUND_INTERVAL): the lower and upper
    # ends of each element's of a list (gonio.report.item_dcc), then an item's (its "(.+)"
    # would take a list's name with its "intervalMin of each element's")
    (rf"(.+): intervalMin of each element's {_BOUND_INTERVAL_RE}; p = (\S+) %",
     "{1}：各元素界限条件区间的下限，" + _BOUND_INTERVAL_ZH + "；p = {2} %"),
    (rf"(.+): intervalMax of each element's {_BOUND_INTERVAL_RE}; p = (\S+) %",
     "{1}：各元素界限条件区间的上限，" + _BOUND_INTERVAL_ZH + "；p = {2} %"),
    (rf"(.+): {_BOUND_INTERVAL_RE}; p = (\S+) %",
     "{1}：界限条件区间，" + _BOUND_INTERVAL_ZH + "；p = {2} %"),
    (rf"(.+): {_MAX_ABS_BOUND_INTERVAL_RE}; p = (\S+) %",
     "{1}：界限条件区间，" + _MAX_ABS_BOUND_INTERVAL_ZH + "；p = {2} %"),
    (rf"(.+): {_BOUND_CHI2_INTERVAL_RE}; p = (\S+) %",
     "{1}：单侧界限条件上限，" + _BOUND_CHI2_INTERVAL_ZH + "；p = {2} %"),
    # the ν of an item stated by a χ² interval (gonio.report.dcc.CHI2_NU, nu_quantity)
    (r"(.+): degrees of freedom ν its chi-square interval was computed with",
     "{1}：其 χ² 区间计算所用的自由度 ν"),
    # ... and of an item stated by another interval (gonio.report.dcc.INTERVAL_NU_EFF)
    (r"(.+): effective degrees of freedom ν_eff its interval's coverage factor was computed "
     r"with", "{1}：其区间的包含因子计算所用的有效自由度 ν_eff"),
    (r"The calibration follows the specification's clauses (.+)\.", "校准按规范的以下条款进行：{1}。"),
    # the parts of a per-item DCC's method after the specification's title ("<title>;
    # protocol …; readings <file> (SHA-256 …, n rows)": its bracket and each part translated
    # in turn)
    (r"protocol (.+)", "校准方案 {1}"),
    (r"readings (.+)", "读数文件 {1}"),
    (r"Statement of conformity: (.+)", "符合性声明：{1}"),
    (r"(pass|fail|conditional pass|conditional fail)(; rule \S+)?; limits (.+?); acceptance "
     r"interval (.+?); specific false-accept probability (.+?)(; false-reject probability "
     r"[^;]+)?; limits from: (.*)",
     "{1}{2}；规定限 {3}；接受区间 {4}；特定误接受概率 {5}{6}；规定限来源：{7}"),
    (r"(pass|fail|conditional pass|conditional fail)(; rule \S+)?; limits (.+?); acceptance: "
     r"(.+?); specific false-accept probability (.+?)(; false-reject probability "
     r"[^;]+)?; limits from: (.*)",
     "{1}{2}；规定限 {3}；接受条件：{4}；特定误接受概率 {5}{6}；规定限来源：{7}"),
    # no probability, with its reason (gonio.analysis.conformity's probability models)
    (r"— \(not given: the extreme of several points; the outcome is decided on its ([\d.]+) % "
     r"interval\)", "—（不给出：多个点的极值；判定依据其 {1} % 区间作出）"),
    (r"— \(not given: its ([\d.]+) % interval \((.+)\) is not that of a normal or chi-square "
     r"distribution; the outcome is decided on its ([\d.]+) % interval\)",
     "—（不给出：其 {1} % 区间（{2}）不是正态分布或 χ² 分布的区间；判定依据其 {3} % 区间作出）"),
    (r"— \(not given: its k = (\S+) is the 95 % coverage factor of a non-normal combined "
     r"distribution \((.+)\), not of N\(y, U/k\); the outcome is decided on y ± U\)",
     "—（不给出：其 k = {1} 为非正态合成分布（{2}）的 95 % 包含因子，不是 N(y, U/k) 的；"
     "判定依据 y ± U 作出）"),
    (r"— \(not given: its k = (\S+) is the 95 % coverage factor of a non-normal combined "
     r"distribution \((.+)\), not of N\(y, U/k\); the outcome is decided on y alone \(simple "
     r"acceptance, no guard band\)\)",
     "—（不给出：其 k = {1} 为非正态合成分布（{2}）的 95 % 包含因子，不是 N(y, U/k) 的；"
     "判定仅依据 y 作出（简单接受，无保护带））"),
    # the bound an accepted interval item states where no probability is computed, with
    # the reason (report.stated.declaration_parts)
    (r"(≤ \S+ %) \((not given: .+)\)", "{1}（{2}）"),
    (r"not given: the extreme of several points; the outcome is decided on its ([\d.]+) % "
     r"interval", "不给出：多个点的极值；判定依据其 {1} % 区间作出"),
    (r"not given: its ([\d.]+) % interval \((.+)\) is not that of a normal or chi-square "
     r"distribution; the outcome is decided on its ([\d.]+) % interval",
     "不给出：其 {1} % 区间（{2}）不是正态分布或 χ² 分布的区间；判定依据其 {3} % 区间作出"),
    (r"Guard band of the items stated by an interval", "以区间表述的项目的保护带"),
    (r"; rule (\S+)", "；判定规则 {1}"),
    (r"; (.+)", "；{1}"),
    (r"(Decision rule: .+) Agreed: (.+)\.", "{1}约定：{2}。"),
    (r"max \|E_i\|", "max |E_i|（最大值）"),
    (r"MPE (.+)", "最大允许误差 {1}"),
    (r"no statement: (.+)", "不作声明：{1}"),
    (r"not measured: (.+)", "未测：{1}"),
    (r"(.+) \(row by row: (.+)\)", "{1}（按行：{2}）"),
    (r"(.+); certificate (.+); traceable to (.+)", "{1}；证书 {2}；溯源至 {3}"),
    (r"(.+); traceable to (.+)", "{1}；溯源至 {2}"),
    (r"rate U_rel = (\S+) \(k = 2\)", "速率相对扩展不确定度 U_rel = {1}（k = 2）"),
    (r"(.+) in results\.json, written per m s⁻² \(g_n = (\S+) m s⁻²\)",
     "results.json 中为 {1}，此处按每 m s⁻² 给出（g_n = {2} m s⁻²）"),
    # an item's statement by its interval (gonio.result.statement.Statement.text's forms)
    (r"upper bound: ≤ (.+?) \(interval \[0, ([^\]]+)\], p ([≈=]) (\S+) %\); the estimate fell "
     r"below zero", "上限：≤ {1}（区间 [0, {2}]，p {3} {4} %）；估计值低于零"),
    (r"upper bound: ≤ (.+?) \(interval \[0, ([^\]]+)\]\); the estimate fell below zero",
     "上限：≤ {1}（区间 [0, {2}]）；估计值低于零"),
    (r"(.+); upper bound: ≤ (.+?) \(interval \[0, ([^\]]+)\], p ([≈=]) (\S+) %\)",
     "{1}；上限：≤ {2}（区间 [0, {3}]，p {4} {5} %）"),
    (r"(.+); interval \[([^\]]+)\](.*?) \(p ([≈=]) (\S+) %\)", "{1}；区间 [{2}]{3}（p {4} {5} %）"),
    (r"Produced by gonio from a virtual bench \(simulated readings\)\. It demonstrates the "
     r"layout and the computations only; it certifies nothing about any instrument\. "
     r"Performance dates are the placeholder (\S+)\.",
     "本文件由 gonio 根据虚拟台架（模拟读数）生成，仅演示版式与计算，不证明任何仪器的计量特性。"
     "日期为占位值 {1}。"),
)


@functools.lru_cache(maxsize=1)
def label_templates() -> tuple[tuple["re.Pattern", str], ...]:
    """The shared certificate labels with fields ("Agreed: {a}") as (regular expression,
    Chinese template): a DCC text formatted from a label is translated with its fields."""
    return templates_of(LABELS)


def templates_of(table: dict) -> tuple[tuple["re.Pattern", str], ...]:
    """The labels of ``table`` ({key: {"en": …, "zh": …}}) with fields, as (regular
    expression, Chinese template) (:func:`label_templates`)."""
    import string

    out = []
    for v in table.values():
        en, zh = v.get("en"), v.get("zh")
        if not isinstance(en, str) or not isinstance(zh, str) or "{" not in en:
            continue
        pat, seen, ok = "", set(), True
        for lit, name, spec, conv in string.Formatter().parse(en):
            pat += re.escape(lit)
            if name is None:
                continue
            if spec or conv or not name.isidentifier():
                ok = False
                break
            pat += f"(?P={name})" if name in seen else f"(?P<{name}>.+?)"
            seen.add(name)
        if ok:
            out.append((re.compile(pat, re.S), zh))
    return tuple(out)


#: "name (clause)": a head and one last bracket (which may itself hold one bracket pair).
_BRACKETED = re.compile(r"(.+?) \(([^()]*(?:\([^()]*\)[^()]*)*)\)", re.S)


def translator(extra: dict | None = None, tables=(), own: dict | None = None, openings=()):
    """``translate(text)`` → its Chinese, or None (a zh DCC's texts beside the English,
    :func:`gonio.report.dcc.bilingual`; screening findings): the certificate labels' English
    → Chinese, the DCC's own texts (:data:`DCC_ZH`), ``extra`` (English → Chinese; a
    key ending in ":", or one of ``openings``, may be the opening words of a longer text, a
    note's "7.2.1:"; any other key is a whole text, so that a name's longer quantities,
    "name (clause): … interval …; p = 95 %", are translated whole, not as the name), the phrase
    ``tables`` (:func:`phrase_zh`); then texts built from parts: the DCC
    phrases (:data:`DCC_PHRASES_ZH`) and the labels with fields, each part
    translated in turn, and "name (clause)" with its name translated. ``own``: the
    specification's own labels (:func:`labels`), translated as the shared ones are. None: no
    Chinese."""
    table = {v["en"]: v["zh"] for v in (LABELS | (own or {})).values()}
    table.update(DCC_ZH)
    table.update(extra or {})
    templates = label_templates() + (templates_of(own) if own else ())

    def translate(text: str, depth: int = 0) -> str | None:
        if text in table:
            return table[text]
        for k, v in (extra or {}).items() if depth == 0 else ():
            if len(k) < len(text) and (k.endswith(":") or k in openings) \
                    and text.startswith(k):
                # a note known by its opening words ("7.2.1:"; never a name)
                return v
        if depth > 4:
            return phrase_zh(text, tables)

        def part(g):
            return (translate(g, depth + 1) or g) if g else g
        for pat, zh in (*tables, *DCC_PHRASES_ZH):
            m = re.fullmatch(pat, text, flags=re.S)
            if m:
                return zh.format(None, *(part(g) or "" for g in m.groups()))
        for rx, zh in templates:
            m = rx.fullmatch(text)
            if m:
                return zh.format(**{k: part(g) for k, g in m.groupdict().items()})
        m = _BRACKETED.fullmatch(text)
        if m:
            head = translate(m.group(1), depth + 1)
            if head is not None:
                return f"{head}（{part(m.group(2))}）"
        m = re.fullmatch(r"([^:;]+): (.+)", text, flags=re.S)    # "label: value"
        if m and m.group(1) in table:
            return f"{table[m.group(1)]}：{part(m.group(2))}"
        for sep, zsep in (("; ", "；"), (", ", "，")):           # "a; b; c", each translated
            if sep in text:
                parts = text.split(sep)
                zh = [translate(p, depth + 1) for p in parts]
                if any(z is not None for z in zh):
                    return zsep.join(z if z is not None else p for z, p in zip(zh, parts))
        return None
    return translate


# --------------------------------------------------------------------------- screening findings

#: What the screening did with a reading (results.json ``findings[].action``), en and zh.
FINDING_ACTIONS = {"set_aside": ("set aside", "剔除"), "flagged": ("flagged", "标记"),
                   "refused": ("refused", "拒收")}

#: Chinese of the findings every specification can give (before the specification's table).
COMMON_FINDINGS_ZH: tuple[tuple[str, str], ...] = (
    (r"column '(.+?)' is not one (\S+) reads: its cells are kept with the readings but no item "
     r"uses them \(a misspelt column\? the columns read: (.+)\)",
     "{1} 列不是 {2} 读取的列：其数据随读数保留，但不用于任何项目（列名拼写有误？读取的列：{3}）"),
)


def finding_text(f: dict, L: dict, table=(), extra: dict | None = None,
                 own: dict | None = None) -> str:
    """One screening finding (results.json ``findings``) as a certificate line in L's
    language: "[set aside] 6.2, column gyro_counts, line 12: message". In Chinese the action,
    line and column are named in Chinese and the message goes through the translation tables
    (the specification's ``table`` of (regular expression, Chinese), ``extra`` English →
    Chinese, its ``own`` labels: :func:`translator`); a message no table knows stays as
    written (data).

    >>> f = {"action": "flagged", "clause": "6.2", "line": None, "column": "round",
    ...      "message": "bias round 3 is missing"}
    >>> finding_text(f, labels("en"))
    '[flagged] 6.2, column round: bias round 3 is missing'
    >>> table = [(r"(\\w+) round (\\d+) is missing", "{1} 第 {2} 测回缺失")]
    >>> finding_text(f, labels("zh"), table, extra={"bias": "零偏"})
    '[标记] 6.2，round 列：零偏 第 3 测回缺失'
    >>> finding_text({"action": "flagged", "clause": "thesis eq. 6.20", "message": "x"},
    ...              labels("zh"), [(r"thesis eq\\. (\\S+)", "论文式 {1}")])
    '[标记] 论文式 6.20：x'
    >>> finding_text({"action": "flagged", "message": "serial: the readings say 'A'"},
    ...              labels("en"))
    "[flagged] serial: the readings say 'A'"
    """
    zh = L.get("_lang") == "zh"
    act = FINDING_ACTIONS.get(f.get("action"), (f.get("action"),) * 2)[1 if zh else 0]
    translate = translator(extra, COMMON_FINDINGS_ZH + tuple(table), own) if zh else None
    clause = f.get("clause") or ""
    parts = [(translate(clause) or clause) if zh and clause else clause]
    if f.get("column"):
        parts.append(f"{f['column']} 列" if zh else f"column {f['column']}")
    if f.get("line") is not None:
        parts.append(f"第 {f['line']} 行" if zh else f"line {f['line']}")
    msg = f.get("message") or ""
    if zh:
        msg = translate(msg) or msg
    where = ("，" if zh else ", ").join(p for p in parts if p)
    if not where:               # a finding of no clause, column or line (the identity's)
        return f"[{act}] {msg}"
    return f"[{act}] {where}{'：' if zh else ': '}{msg}"
