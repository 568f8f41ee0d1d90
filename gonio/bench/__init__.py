"""The virtual rate-gyro bench shared by the rate specifications (JJF 1535-2015 and
IEC 62047-20 through their family package, and plug-ins through the kit).

``rate_gyro``     the virtual rate gyro (scale factor, bias, noise, temperature and supply)
``equipment``     the laboratory's equipment: rate and position tables, chamber, supply
``rate_session``  runs a programme of segments on them → readings, truth
``rate_truth``    closed forms of the gyro's noise-free responses (the truths)

A specification's own virtual bench lives in its package (the optical draft's goniometer on
a precision rotary table, the triad's gyros on a rate table and in a chamber).
"""
