"""An instrument's stored limits refuse an upper limit below zero for an item its
specification declares cannot be negative (``Specification.nonnegative_items``: a dispersion,
a range, a noise level), when stored (register, edit, the web form), in the one line the
laboratory file's check prints, not only when a calibration is decided later; a limit below
zero for a signed item, and a non-negative upper limit, are stored as given."""

from __future__ import annotations

import html
import json
import re

import pytest
from sqlalchemy import func, select

from gonio.errors import GonioError
from gonio.records import services
from gonio.records.models import Instrument

from .conftest import make_people
from .test_web_security import app  # noqa: F401  (the app fixture)


def _instrument(store, people, spec_key, cust_id, limits=()):
    return services.register_instrument(store, people["tech"], customer_id=cust_id,
                                        serial="G-0001", spec_key=spec_key,
                                        limits=list(limits))


def _count(store) -> int:
    with store.session() as s:
        return s.scalar(select(func.count()).select_from(Instrument))


# (specification, an item it declares non-negative, a signed item of it)
CASES = [("ogam-draft", "zero_stability", "scale_factor"),
         ("jjf1535-2015", "bias_stability", "bias"),
         ("iec62047-20", "arw", "bias"),
         ("triad-alignment", "ARW_y_t2", "M_xy")]


@pytest.mark.parametrize("spec_key, nonneg, signed", CASES)
def test_negative_upper_of_a_nonnegative_item_refused_when_stored(sqlite_store, spec_key,
                                                                  nonneg, signed):
    """Registration and an edit refuse ``upper`` < 0 for the item, naming the entry's
    ``upper`` and the item in one line, nothing stored; the same limits with the entry
    deleted, or with a signed item's negative upper, are stored."""
    people = make_people(sqlite_store)
    cust_id = services.add_customer(sqlite_store, people["tech"], "Example Navigation Co.").id
    bad = [{"item": signed, "lower": -2.0, "upper": -1.0}, {"item": nonneg, "upper": -0.01}]
    with pytest.raises(GonioError) as exc:
        _instrument(sqlite_store, people, spec_key, cust_id, limits=bad)
    msg = str(exc.value)
    assert msg.startswith(f"key limits[1].upper: {nonneg} cannot be negative"), msg
    assert "-0.01" in msg and "\n" not in msg
    assert _count(sqlite_store) == 0
    inst = _instrument(sqlite_store, people, spec_key, cust_id, limits=bad[:1])    # the entry deleted
    with pytest.raises(GonioError, match=rf"^key limits\[1\]\.upper: {nonneg} cannot be "):
        services.update_instrument(sqlite_store, people["tech"], inst.id, limits=bad)
    with sqlite_store.session() as s:
        assert json.loads(s.get(Instrument, inst.id).limits_json)[0]["upper"] == -1.0
        assert len(json.loads(s.get(Instrument, inst.id).limits_json)) == 1
    services.update_instrument(sqlite_store, people["tech"], inst.id,
                               limits=[bad[0], {"item": nonneg, "upper": 0.01}])
    with sqlite_store.session() as s:
        assert json.loads(s.get(Instrument, inst.id).limits_json)[1]["upper"] == 0.01


def test_declared_items_are_the_ones_results_mark():
    """The declaration the records check is the one the rate specifications' items are marked
    with (the same set), and the triad's patterns match the keys its thermal model marks."""
    from fnmatch import fnmatchcase

    from gonio.specs import get, nonnegative_items
    from gonio.specs.iec62047_20 import items as iec_items
    from gonio.specs.jjf1535 import items as jjf_items

    assert set(nonnegative_items("jjf1535-2015")) == jjf_items.NONNEGATIVE
    assert set(nonnegative_items("iec62047-20")) == iec_items.NONNEGATIVE
    pats = nonnegative_items("triad-alignment")
    assert [any(fnmatchcase(k, p) for p in pats) for k in ("ARW_x_t1", "ARW_z_t12", "K_x_t1_v1",
                                                           "b_y_t2_v1")] == [
        True, True, False, False]
    assert nonnegative_items("no-such-spec") == ()
    for key in ("ogam-draft", "jjf1535-2015", "iec62047-20", "triad-alignment"):
        spec = get(key)
        assert all(spec.knows_item(k) for k in spec.nonnegative_items), key


def test_the_web_form_says_the_refusal(app, sqlite_store):  # noqa: F811
    """The register form comes back (400) with the one line, nothing registered."""
    from .test_web_security import csrf_of, login

    tech = login(app, "tech")
    cust = services.add_customer(sqlite_store, services.user(sqlite_store, "tech"), "C")
    form = {"csrf": csrf_of(tech), "customer_id": str(cust.id), "serial": "W-1",
            "spec_key": "ogam-draft", "limit_item_0": "repeatability", "limit_upper_0": "0.3",
            "limit_item_1": "zero_stability", "limit_upper_1": "-0.01"}
    r = tech.post("/instruments", data=form)
    assert r.status_code == 400
    m = re.search(r'<p class="error" role="alert">(.*?)</p>', r.text, re.S)
    assert m, r.text[:2000]
    msg = html.unescape(m.group(1))
    assert msg.startswith("key limits[1].upper: zero_stability cannot be negative"), msg
    assert "\n" not in msg
    assert _count(sqlite_store) == 0
    r = tech.post("/instruments", data={**form, "limit_upper_1": "0.01"})
    assert r.status_code == 303, r.text[:500]
    assert _count(sqlite_store) == 1
