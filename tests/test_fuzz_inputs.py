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


def test_further_families_raise_only_pinflex_errors(record_property):
    """Trajectory headers and units, Unicode digits, parameter references in every attribute,
    [simulation] bounds, study files, URDF structure, output targets, API argument types and
    command lines: 0 foreign, 0 silent.

    A permuted trajectory header must load into the right columns; a reference must be
    refused exactly when its literal is; a CLI refusal is exit 2 and one line.
    """
    from fuzz_inputs import run_families

    out = run_families(600, seed=20261202, cli=40)
    fam = out["by_family"]
    print(f"\nfamilies: {out['variants']} variants, {out['foreign']} foreign, "
          f"{out['silent_acceptances']} silent, {out['seconds']} s")
    for key in ("variants", "foreign", "silent_acceptances"):
        record_property(f"families_{key}", out[key])
    assert out["foreign"] == 0, out["foreign_examples"]
    assert out["silent_acceptances"] == 0, out["silent_examples"]
    for family in ("trajectory_headers", "unicode_digits", "parameter_reference",
                   "simulation_bounds", "api_types", "cli"):
        assert fam[family]["variants"] >= 30, family
    assert fam["trajectory_headers"].get("accepted", 0) > 0  # permuted headers load
    assert fam["unicode_digits"].get("accepted", 0) == 0
    assert fam["api_types"].get("accepted", 0) == 0
    for family in ("study_files", "output_targets"):  # every variant is a refusal
        assert fam[family]["variants"] >= 15 and fam[family].get("accepted", 0) == 0, family
    assert fam["parameter_reference"].get("refused_only_as_reference", 0) == 0
    assert fam["parameter_reference"]["refused"] == fam["parameter_reference(literal)"]["refused"]
