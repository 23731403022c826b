import pytest
from hypothesis import given
from hypothesis import strategies as st

from crmgrasp import CrmgraspError
from crmgrasp.model.history import KOrderEncoder


def test_paper_sizes():
    enc = KOrderEncoder(24, 4, 2)
    assert enc.unpadded_size == 24 * 4 * 24 * 4 == 9216
    assert enc.size == 24 * 5 * 25 * 5
    assert KOrderEncoder(24, 4, 0).size == 24 and KOrderEncoder(24, 4, 1).size == 24 * 5


@given(st.integers(0, 6), st.integers(1, 30), st.integers(1, 6), st.data())
def test_roundtrip_and_push(k, n_obs, n_act, data):
    enc = KOrderEncoder(n_obs, n_act, k)
    h = enc.start(data.draw(st.integers(0, n_obs - 1)))
    seen = [h[0]]
    acts = []
    for _ in range(data.draw(st.integers(0, 5))):
        a, o = data.draw(st.integers(0, n_act - 1)), data.draw(st.integers(0, n_obs - 1))
        before = enc.encode(h)
        h = enc.push(h, a, o)
        assert enc.push_code(before, a, o) == enc.encode(h)  # the arithmetic push
        acts.append(a)
        seen.append(o)
        code = enc.encode(h)
        assert 0 <= code < enc.size and enc.decode(code) == h
    assert h[0] == seen[-1]
    if k >= 1 and acts:
        assert h[1] == acts[-1]
    if k >= 2 and len(seen) >= 2:
        assert h[2] == seen[-2]
    assert enc.is_padded(h) == (k > 0 and len(acts) < k)


@given(st.integers(0, 4), st.integers(1, 8), st.integers(1, 4), st.data())
def test_kept_is_what_the_next_history_keeps(k, n_obs, n_act, data):
    """Two histories with the same ``kept`` have the same next history after every CRM and
    observation, and two with different ones never do (``backoff-vi`` and ``pooled-vi`` share
    planning entries on it)."""
    enc = KOrderEncoder(n_obs, n_act, k)
    h, g = (data.draw(st.integers(0, enc.size - 1)) for _ in range(2))
    a, o = data.draw(st.integers(0, n_act - 1)), data.draw(st.integers(0, n_obs - 1))
    assert (enc.push_code(h, a, o) == enc.push_code(g, a, o)) == (enc.kept(h) == enc.kept(g))


def test_distinct_histories_get_distinct_codes():
    enc = KOrderEncoder(3, 2, 2)
    codes = set()
    for o0 in range(3):
        for a in range(2):
            for o1 in range(3):
                for b in range(2):
                    codes.add(enc.encode((o1, a, o0, b)))
    assert len(codes) == enc.unpadded_size


def test_bad_encoder():
    with pytest.raises(CrmgraspError, match=r"k must be an integer in \[0, 10\], got -1"):
        KOrderEncoder(24, 4, -1)
    with pytest.raises(CrmgraspError, match="outside"):
        KOrderEncoder(24, 4, 1).start(24)
    with pytest.raises(CrmgraspError, match="outside"):
        KOrderEncoder(24, 4, 1).decode(10**6)
