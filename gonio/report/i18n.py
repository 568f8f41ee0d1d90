"""Certificate labels in English and Chinese, the CJK font, and the ONE number-display rule.

Contents
========
=========================  ==========================================================
:data:`LABELS`             label key → {"en": ..., "zh": ...}; the Chinese terms are the draft's
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
                                    p_text, round_half_up, state)
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
    "chamber_profile": {"en": "Temperature chamber points", "zh": "温度试验箱温度点"},
    "chamber_bound": {"en": " (deviation within ±{b} °C)", "zh": "（偏差不超过 ±{b} °C）"},
    "not_stated": {"en": "not stated", "zh": "未说明"},
    "results": {"en": "Results of calibration (Annex B)", "zh": "校准结果（附录B）"},
    "no": {"en": "No.", "zh": "序号"},
    "item": {"en": "Item", "zh": "校准项目"},
    "clause": {"en": "Clause", "zh": "条款"},
    "result": {"en": "Result", "zh": "校准结果"},
    "unit": {"en": "Unit", "zh": "单位"},
    "not_measured": {"en": "not measured", "zh": "未测"},
    "uncertainty": {"en": "Measurement uncertainty", "zh": "测量不确定度"},
    "U_line": {"en": "Uncertainty of the angle-position deviation: U = {U}″, k = {k}",
               "zh": "角位置偏差的测量不确定度：U = {U}″，k = {k}"},
    "K_as_mounted": {"en": "The scale factor K is stated as mounted: sensing plane within {psi}° "
                           "of the table plane (Annex A.1). The instrument's own K (sensing axis "
                           "along the rotation axis) is larger by up to {ppm} ppm (1/cos ψ − 1); "
                           "this is not included in U.",
                     "zh": "标度因数 K 为安装状态下的值：敏感平面与转台台面的夹角不超过 {psi}°"
                           "（附录A.1）。仪器自身的 K（敏感轴沿转轴）最多大 {ppm} ppm"
                           "（1/cos ψ − 1），未计入 U。"},
    "std_mpe": {"en": "MPE ±{v}″", "zh": "最大允许误差 ±{v}″"},
    "screening_h": {"en": "Screening of the readings", "zh": "读数筛查"},
    "more_findings": {"en": "… {n} more in results.json (findings)",
                      "zh": "……另有 {n} 条，见 results.json"},
    "screening_note": {"en": "Screening of the readings: {n} reading(s) set aside (not used; "
                             "listed in results.json with line and reason) and {m} finding(s) "
                             "on the completeness of the programme; the results above rest "
                             "on the remaining data.",
                       "zh": "读数筛查：{n} 个读数被剔除（未使用，行号与原因见 results.json），"
                             "{m} 项关于校准程序完整性的提示；以上结果基于其余数据。"},
    "u_c_line": {"en": "combined standard uncertainty u_c = {u}″ (Annex A.6)",
                 "zh": "合成标准不确定度 u_c = {u}″（附录A.6）"},
    "budget": {"en": "Uncertainty budget (Annex A)", "zh": "不确定度分量（附录A）"},
    "component": {"en": "Component", "zh": "分量"},
    "source": {"en": "Source", "zh": "来源"},
    "type": {"en": "Type", "zh": "类别"},
    "u_i": {"en": "u_i (″)", "zh": "u_i (″)"},
    # per-item budgets of the rate certificates: u_i in its input's unit, |c_i|·u_i in the item's
    "budget_items": {"en": "Uncertainty budget of each item (from this calibration's data)",
                     "zh": "各校准项目的不确定度分量（依据本次校准数据）"},
    "u_i_item": {"en": "u_i (input's unit)", "zh": "u_i（输入量单位）"},
    "readings_taken": {"en": "Readings taken of the draft's ambiguities",
                       "zh": "对规范草案中不明确之处的理解"},
    "readings_taken_std": {"en": "Readings taken of the specification's text",
                           "zh": "对规范条文的理解"},
    "details": {"en": "Details of the measurements", "zh": "测量详细数据"},
    "figures": {"en": "Figures", "zh": "图"},
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
    "amendment": {"en": "This certificate amends and replaces certificate {old}, which is "
                        "withdrawn. Reason for the amendment: {reason}",
                  "zh": "本证书修订并取代证书 {old}，原证书作废。修订原因：{reason}"},
    "amendment_title": {"en": "Amendment", "zh": "修订"},
    "draft_short": {"en": "DRAFT", "zh": "草稿"},
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
    "source_file": {"en": "Readings file", "zh": "读数文件"},
    "truth": {"en": "virtual-bench truth (systematic part)", "zh": "虚拟台架真值（系统部分）"},
    # the seven items (Annex B order) — the draft's own Chinese terms
    "scale_factor": {"en": "Scale factor K", "zh": "标度因数 K"},
    "scale_factor_nonlinearity": {"en": "Scale-factor nonlinearity K_l",
                                  "zh": "标度因数非线性度 K_l"},
    "zero_stability": {"en": "Zero stability B_s", "zh": "零位稳定性 B_s"},
    "angle_deviation": {"en": "Angle-position deviation E", "zh": "角位置偏差 E"},
    "repeatability": {"en": "Angle-position repeatability R", "zh": "角位置重复性 R"},
    "rate_consistency": {"en": "Rate consistency C_v", "zh": "速率一致性 C_v"},
    "pointing_consistency": {"en": "Pointing consistency C_g", "zh": "指向一致性 C_g"},
    # units as shown
    "u_counts/deg": {"en": "counts/°", "zh": "脉冲数/(°)"},
    "u_%": {"en": "%", "zh": "%"},
    "u_deg/h": {"en": "°/h", "zh": "(°)/h"},
    "u_deg/s": {"en": "°/s", "zh": "(°)/s"},
    "u_arcsec": {"en": "″", "zh": "″"},
    "u_ppm": {"en": "ppm", "zh": "ppm"},
    # item notes
    "note_zero_range": {"en": "range/T (definition 3.3): {v} °/h", "zh": "极差/T（定义3.3）：{v} (°)/h"},
    "note_zero_model": {"en": "noise model of the 7.3 record (beside, not stated): {v} °/h",
                        "zh": "7.3 连续记录的噪声模型估计（并列给出，不作结果）：{v} (°)/h"},
    "note_kl_draft": {"en": "the draft's range as measured (beside, not stated): {v} %",
                      "zh": "按草案公式的测得极差（并列给出，不作结果）：{v} %"},
    "note_at": {"en": "at {p}°", "zh": "位于 {p}°"},
    "note_spread": {"en": "spread max E − min E = {v}″", "zh": "极差 max E − min E = {v}″"},
    # figures
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
    "lg_series": {"en": "series", "zh": "组"},
    "lg_mean": {"en": "mean E_i", "zh": "平均 E_i"},
    "lg_elliptic": {"en": "elliptic model, ψ = {psi}°", "zh": "椭圆模型, ψ = {psi}°"},
    "lg_rigid": {"en": "rigid body, after 7.1 (≡ 0)", "zh": "刚体模型，经7.1标定后（≡ 0）"},
    "lg_rigid_uncal": {"en": "rigid body, uncalibrated", "zh": "刚体模型, 未标定"},
    "lg_mean_K": {"en": "K (mean)", "zh": "K（平均）"},
    "lg_drift": {"en": "linear drift {v} °/h", "zh": "线性漂移 {v} (°)/h"},
    "lg_U": {"en": "U", "zh": "U"},
    "lg_R": {"en": "R = max", "zh": "R = 最大值"},
    "lg_reference": {"en": "(reference)", "zh": "（参考）"},
    "no_data": {"en": "not measured", "zh": "未测"},
    "up": {"en": "up", "zh": "竖直向上"}, "north": {"en": "north", "zh": "正北"},
    "south": {"en": "south", "zh": "正南"}, "east": {"en": "east", "zh": "正东"},
    "west": {"en": "west", "zh": "正西"},
    # results table, uncertainty and the ± form (7.4)
    "U_col": {"en": "Expanded uncertainty U", "zh": "扩展不确定度 U"},
    "U_cell": {"en": "{U} (k = {k}, p ≈ {p} %)", "zh": "{U}（k = {k}，p ≈ {p} %）"},
    "E_note": {"en": "signed extreme {s}″ at {p}°", "zh": "带符号极值 {s}″，位于 {p}°"},
    "U_line_p": {"en": "Uncertainty of the angle-position deviation: U = {U}″, k = {k}, "
                       "coverage probability {p}",
                 "zh": "角位置偏差的测量不确定度：U = {U}″，k = {k}，包含概率{p}"},
    # where the coverage factor k comes from
    "k_fixed": {"en": "k: fixed by laboratory", "zh": "k：由实验室规定"},
    "k_welch": {"en": "k: t-factor of the effective degrees of freedom (Welch–Satterthwaite)",
                "zh": "k：按有效自由度（韦尔奇–萨特思韦特公式）取 t 分布因子"},
    "k_each_item": {"en": "U: expanded uncertainty, k = t95(ν_eff) of each item's effective "
                          "degrees of freedom (shown per item in the budgets below); {clause}.",
                    "zh": "U：扩展不确定度，k = t95(ν_eff)，按各项的有效自由度取值（见下方各项"
                          "不确定度分量）；{clause}。"},
    "k_chi_square": {"en": "An item stated by an interval has that one statement, shown in the "
                           "result with its probability, and no U and no k: a standard "
                           "deviation of a few repeats (a repeatability, a stability) or a half "
                           "range by its one-sided 95 % upper limit (σ's χ² distribution, "
                           "JCGM 100 E.4.3; the range of normal values for a half range), on "
                           "which any conformity decision is made; a quantity that cannot be "
                           "negative whose U exceeds its value by its upper bound, value + U "
                           "(the interval value ± U without its impossible negative part, "
                           "JCGM 100 4.3.9).",
                     "zh": "以区间表述的项目只有这一个表述，在结果栏中连同包含概率给出，无 U，无 k："
                           "少数重复测量的标准偏差（重复性、稳定性）或半极差给出其单侧 95 % 上限"
                           "（标准偏差按 χ² 分布，JCGM 100 E.4.3；半极差按正态极差分布），对上限的判定"
                           "亦以此为据；不能为负且 U 大于其值的量给出其上限 值 + U（区间 值 ± U "
                           "去掉不可能的负值部分，JCGM 100 4.3.9）。"},
    "budget_kind_draft": {"en": "Budget as the draft's Annex A states it.",
                          "zh": "按规范草案附录A的不确定度评定。"},
    "budget_kind_physical": {"en": "Budget of this calibration's physical model; lines marked "
                                   "\"beyond the draft\" are not in Annex A.",
                             "zh": "按本次校准的物理模型评定；标“超出草案”的分量不在附录A中。"},
    "beyond_draft": {"en": "beyond the draft", "zh": "超出草案"},
    "u_c_word": {"en": "combined standard uncertainty", "zh": "合成标准不确定度"},
    "src_own_A": {"en": "scatter of the item's own readings (Type A)",
                  "zh": "本项目读数的分散性（A类）"},
    "src_own_B": {"en": "bound from the specification's procedure (Type B)",
                  "zh": "按规范程序给出的界限（B类）"},
    "no_E_U": {"en": "Angle-position deviation not measured: no uncertainty stated.",
               "zh": "未测角位置偏差：不给出测量不确定度。"},
    # method
    "method": {"en": "Method", "zh": "校准方法"},
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
    "m_temp": {"en": "Temperature", "zh": "温度"},
    "m_temp_v": {"en": "required ({t} ± {tol}) °C (Table 2); during calibration {m}",
                 "zh": "要求 ({t} ± {tol}) °C（表2）；校准时 {m}"},
    "m_readings": {"en": "Readings taken of the draft's ambiguities: see the section below.",
                   "zh": "对草案不明确之处的理解：见下节。"},
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
    "c_no_statement": {"en": "no statement: {r}", "zh": "不作声明：{r}"},
    "c_no_U": {"en": "no statement: the item has no stated uncertainty",
               "zh": "不作声明：该项目无测量不确定度"},
    "c_not_measured": {"en": "no statement: not measured", "zh": "不作声明：未测"},
    "pass": {"en": "pass", "zh": "合格"},
    "fail": {"en": "fail", "zh": "不合格"},
    "conditional pass": {"en": "conditional pass", "zh": "有条件合格"},
    "conditional fail": {"en": "conditional fail", "zh": "有条件不合格"},
    # detail tables
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
    "rows_word": {"en": "{n} rows", "zh": "{n} 行"},
    "virtual_lab": {"en": "gonio virtual bench", "zh": "gonio 虚拟台架"},
    "virtual_place": {"en": "virtual bench", "zh": "虚拟台架"},
    "virtual_trace": {"en": "none (virtual bench)", "zh": "无（虚拟台架）"},
    "draft_for_comment": {"en": "(draft for comment)", "zh": "（征求意见稿）"},
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


def labels(lang: str = "en") -> dict[str, str]:
    """The labels of ``lang`` ("en" or "zh") as a flat mapping.

    >>> labels("zh")["scale_factor_nonlinearity"]
    '标度因数非线性度 K_l'
    >>> labels("fr")
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: key lang: expected one of en, zh, got 'fr'
    """
    if lang not in LANGUAGES:
        raise GonioError(f"expected one of {', '.join(LANGUAGES)}, got {lang!r}", key="lang")
    return {k: v[lang] for k, v in LABELS.items()} | {"_lang": lang}


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


_NUM = re.compile(r"^([+-]?\d+(?:\.\d+)?)(?:×10([⁻⁰¹²³⁴⁵⁶⁷⁸⁹]+))?$")
_UNSUP = str.maketrans("⁻⁰¹²³⁴⁵⁶⁷⁸⁹", "-0123456789")


def parse_display(text: str) -> float:
    """A displayed number back to a float (inverse of :func:`display_number`).

    >>> parse_display("2.18×10⁻⁵"), parse_display("+0.87"), parse_display("76434.843")
    (2.18e-05, 0.87, 76434.843)
    """
    m = _NUM.match(text.strip())
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
    m = _NUM.match(text.strip())
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
    ``"k"`` (a coverage factor: 3 significant digits, trailing zeros dropped), ``"nu"``
    (ν_eff: its integer part, GUM G.6.4), ``"sci<E>.<N>"`` (the mantissa at N decimals ×
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
    """"approximately 95 %" for a coverage probability 0.95 (JCGM 100 6.2.2).

    >>> coverage_text(0.95), coverage_text(0.9545, "zh"), coverage_text(None)
    ('approximately 95 %', '约 95 %', '—')
    """
    if p is None:
        return "—"
    pct = p_text(p)
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
    phrase ``table``, see :func:`phrase_zh`); the optical budget's "[beyond the draft: …]"
    note is shown once, as the label ``beyond_draft``.

    >>> source_text("zero drift (A.4.3)", labels("en"))
    'zero drift (A.4.3)'
    >>> source_text("x -> dK [beyond the draft: 7.1 (y)]", labels("en"))
    'x -> dK (beyond the draft)'
    """
    base, _, note = src.partition(" [beyond the draft")
    out = (phrase_zh(base, table) or base) if L.get("_lang") == "zh" else base
    if not note:
        return out
    return out + (f"（{L['beyond_draft']}）" if L.get("_lang") == "zh" else f" ({L['beyond_draft']})")


def reason_text(reason: str, L: dict, table=(), extra: dict | None = None) -> str:
    """Why an item was not measured, in the certificate's language: in Chinese through the
    specification's ``table`` and the shared ones (:func:`translator`, :data:`REASONS_ZH`);
    a reason no table knows stays as written."""
    if L.get("_lang") == "zh":
        return translator(extra, tuple(table) + REASONS_ZH)(reason) or reason
    return reason


# --------------------------------------------------------------------------- DCC texts (zh)

#: The fixed English texts of every DCC (gonio.report.dcc, rate_dcc, item_dcc) → Chinese,
#: written beside the English in a zh DCC (:func:`gonio.report.dcc.bilingual`).
DCC_ZH: dict[str, str] = {
    "serial number": "出厂编号",
    "Reading taken of the specification's text": "对规范条文的理解",
    "Reading taken of the sources": "对参考文献的理解",
    "Reading taken of the draft's text": "对规范草案条文的理解",
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
    "per-point table": "逐点数据表",
    "round angle θ_i": "测回角 θ_i",
    "B_s per series": "各组 B_s",
    "linear drift per series": "各组线性漂移",
    "E = ± max|E_i| (draft 7.4)": "E = ± max|E_i|（规范草案 7.4）",
    "signed extreme of E_i": "E_i 的带符号极值",
    "position of the extreme": "极值所在位置",
    "position": "位置",
    "table rate": "转台角速度",
    "axis direction": "轴向",
    "upper bound (coverage interval [0, upper bound]: a non-negative quantity whose U exceeds "
    "its value)": "上限（包含区间 [0, 上限]：非负量，U 大于其值）",
    "Calibration of an optical-gyroscope angle measuring instrument": "光学陀螺测角仪校准",
    "MEMS rate gyro (virtual)": "微机电速率陀螺（虚拟）",
    "MEMS gyro triad (virtual)": "微机电三轴陀螺组件（虚拟）",
    "RLG goniometer (virtual)": "激光陀螺测角仪（虚拟）",
    "FOG goniometer (virtual)": "光纤陀螺测角仪（虚拟）",
    "precision low-speed rotary table (virtual)": "精密低速转台（虚拟）",
    "gonio virtual bench": "gonio 虚拟台架",
    "rate table, two-axis position table, angular vibration table, chamber (virtual)":
        "速率转台、双轴位置转台、角振动台、温箱（虚拟）",
}

#: DCC texts built from parts: (regular expression, Chinese template with the groups as {1},
#: {2}…; each group is itself translated where it can be, :func:`gonio.report.dcc.label_translator`).
DCC_PHRASES_ZH: tuple[tuple[str, str], ...] = (
    (r"The calibration follows the specification's clauses (.+)\.", "校准按规范的以下条款进行：{1}。"),
    (r"Statement of conformity: (.+)", "符合性声明：{1}"),
    (r"(pass|fail|conditional pass|conditional fail)(; rule \S+)?; limits (.+?); acceptance "
     r"interval (.+?); specific false-accept probability ([^;]+)(; false-reject probability "
     r"[^;]+)?; limits from: (.*)",
     "{1}{2}；规定限 {3}；接受区间 {4}；特定误接受概率 {5}{6}；规定限来源：{7}"),
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
    (r"Produced by gonio from a virtual bench \(simulated readings\)\. It demonstrates the "
     r"layout and the computations only; it certifies nothing about any instrument\. "
     r"Performance dates are the placeholder (\S+)\.",
     "本文件由 gonio 根据虚拟台架（模拟读数）生成，仅演示版式与计算，不证明任何仪器的计量特性。"
     "日期为占位值 {1}。"),
)


@functools.lru_cache(maxsize=1)
def label_templates() -> tuple[tuple["re.Pattern", str], ...]:
    """The certificate labels with fields ("Agreed: {a}") as (regular expression, Chinese
    template): a DCC text formatted from a label is translated with its fields."""
    import string

    out = []
    for v in LABELS.values():
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


def translator(extra: dict | None = None, tables=()):
    """``translate(text)`` → its Chinese, or None (a zh DCC's texts beside the English,
    :func:`gonio.report.dcc.bilingual`; screening findings): the certificate labels' English
    → Chinese, the DCC's own texts (:data:`DCC_ZH`), ``extra`` (English → Chinese; a
    key may be the opening words of a longer text, e.g. a note's "7.2.1:"), the phrase
    ``tables`` (:func:`phrase_zh`); then texts built from parts: the DCC
    phrases (:data:`DCC_PHRASES_ZH`) and the labels with fields, each part
    translated in turn, and "name (clause)" with its name translated. None: no Chinese."""
    table = {v["en"]: v["zh"] for v in LABELS.values()}
    table.update(DCC_ZH)
    table.update(extra or {})
    templates = label_templates()

    def translate(text: str, depth: int = 0) -> str | None:
        if text in table:
            return table[text]
        for k, v in (extra or {}).items() if depth == 0 else ():
            if len(k) < len(text) and text.startswith(k) and not k.isidentifier():
                # a note known by its opening words ("7.2.1:"; not a bare name)
                return v
        if depth > 4:
            return phrase_zh(text, tables)

        def part(g):
            return (translate(g, depth + 1) or g) if g else g
        for pat, zh in (*tables, *DCC_PHRASES_ZH, *REASONS_ZH):
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

#: The optical draft's screening messages (its screen module) in Chinese; each
#: group is itself translated where it can be (an axis "up", a test's item name).
FINDINGS_ZH: tuple[tuple[str, str], ...] = (
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
    (r"(\w+) at (\S+) °/s, axis (\w+)", "{1}，{2} °/s，{3}轴"),
    (r"zero_stability series (\d+)", "零位稳定性第 {1} 组"),
    (r"(\w+) \((\S+)\): the programme's condition (\S+) °/s, axis (\w+) has no reading",
     "{1}（{2}）：校准方案的测量条件 {3} °/s、{4}轴没有读数"),
    (r"(\w+) \((\S+)\) at (\S+) °/s, axis (\w+): round (\d+) \((\S+)°\) is missing from every "
     r"series; the item rests on (\d+) of the programme's (\d+) rounds",
     "{1}（{2}），{3} °/s，{4}轴：第 {5} 测回（{6}°）在各组中均缺失；该项目仅依据校准方案 {8} "
     "个测回中的 {7} 个"),
)


#: Why an optical item was not measured (the draft's items module), in Chinese.
REASONS_ZH: tuple[tuple[str, str], ...] = (
    (r"no (\w+) rows in file", "文件中没有 {1} 数据行"),
    (r"scale factor not measured: (.+)", "标度因数未测：{1}"),
    (r"needs at least 2 scale_factor rounds, file has 1", "至少需要 2 个标度因数测回，文件只有 1 个"),
    (r"zero_stability needs at least 2 readings in a series", "零位稳定性每组至少需要 2 个读数"),
    (r"no angle_deviation rows at the 7\.4 condition \((.+)\)", "没有 7.4 测量条件（{1}）下的 "
     "angle_deviation 数据行"),
    (r"repeatability needs at least 2 angle_deviation series, file has 1",
     "重复性至少需要 2 组 angle_deviation 数据，文件只有 1 组"),
    (r"no (\w+) rows at (.+)", "没有 {2} 下的 {1} 数据行"),
    (r"no reference condition \((.+)\): neither (\w+) nor angle_deviation rows there",
     "没有参考条件（{1}）：该条件下既无 {2} 也无 angle_deviation 数据行"),
    (r"(\S+) needs at least 2 conditions, file has only (.+)", "{1} 至少需要 2 个测量条件，文件只有 {2}"),
    (r"(\S+) needs at least 2 complete conditions", "{1} 至少需要 2 个完整的测量条件"),
    (r"no calibration position common to every condition", "各测量条件没有共同的校准位置"),
    (r"(\S+) deg/s, axis (\w+)", "{1} °/s，{2}轴"),
    (r"(\S+) deg/s", "{1} °/s"),
)


def finding_text(f: dict, L: dict, table=(), extra: dict | None = None) -> str:
    """One screening finding (results.json ``findings``) as a certificate line in L's
    language: "[set aside] 7.4, column gyro_counts, line 12: message". In Chinese the action,
    line and column are named in Chinese and the message goes through the translation tables
    (the specification's ``table`` of (regular expression, Chinese), :data:`FINDINGS_ZH`,
    ``extra`` English → Chinese); a message no table knows stays as written (data).

    >>> f = {"action": "flagged", "clause": "7.4", "line": None, "column": "round",
    ...      "message": "angle_deviation (7.4) at 60 °/s, axis up: round 3 (270°) is missing "
    ...                 "from every series; the item rests on 3 of the programme's 4 rounds"}
    >>> finding_text(f, labels("en"))[:42]
    '[flagged] 7.4, column round: angle_deviati'
    >>> finding_text(f, labels("zh"), extra={"angle_deviation": "角位置偏差 E"})[:62]
    '[标记] 7.4，round 列：角位置偏差 E（7.4），60 °/s，竖直向上轴：第 3 测回（270°）在各组中均缺失'
    """
    zh = L.get("_lang") == "zh"
    act = FINDING_ACTIONS.get(f.get("action"), (f.get("action"),) * 2)[1 if zh else 0]
    parts = [f.get("clause") or ""]
    if f.get("column"):
        parts.append(f"{f['column']} 列" if zh else f"column {f['column']}")
    if f.get("line") is not None:
        parts.append(f"第 {f['line']} 行" if zh else f"line {f['line']}")
    msg = f.get("message") or ""
    if zh:
        msg = translator(extra, tuple(table) + FINDINGS_ZH)(msg) or msg
    where = ("，" if zh else ", ").join(p for p in parts if p)
    return f"[{act}] {where}{'：' if zh else ': '}{msg}"
