"""Seeded fuzz test: >= 1000 malformed variants of the shipped inputs, all named or loaded."""

from fuzz_inputs import MUST_REFUSE, run


def test_fuzzed_inputs_raise_only_pinflex_errors(record_property):
    """1000 mutations of urdf/ and examples/*.toml raise only PinflexError subclasses.

    No foreign exception, and no misspelling (element, attribute, namespace, TOML key) or
    non-number is accepted in silence.
    """
    out = run(1000, seed=20261201)
    print(f"\nfuzz: {out['variants']} variants, {out['refused']} refused, {out['accepted']} "
          f"accepted, {out['foreign']} foreign, {out['silent_acceptances']} silent")
    for key in ("variants", "refused", "accepted", "foreign", "silent_acceptances"):
        record_property(key, out[key])
    assert out["variants"] >= 1000
    assert out["foreign"] == 0, out["foreign_examples"]
    assert out["silent_acceptances"] == 0, out["silent_examples"]
    assert out["misspellings"] >= 200
    for kind in MUST_REFUSE & set(out["by_kind"]):
        assert out["by_kind"][kind].get("accepted", 0) == 0, kind
    assert out["by_kind"]["misspelt_element"]["refused"] > 0
