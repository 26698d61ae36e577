"""long_name is a label: xarray, ncview, Panoply and CF tools print it on axes and in lists
(``da.plot()`` writes "<long_name> [<units>]"), so every declared variable's long_name is short
and says what the variable is, never how it is computed, when it is NaN or where to read more:
that goes in ``attrs={"comment": ...}`` (docs/architecture.md)."""

from __future__ import annotations

import re

from roughcontact.stage import coords, stages

#: a long_name is at most this long (characters)
MAX_LABEL = 49

#: what marks an explanation in a label: a second clause, a sentence, an example, a default, a
#: condition, an attribute or a document to read, an equation reference
EXPLANATION = re.compile(r";|: |\. |\be\.g\.|\bi\.e\.|\(default|\battribute\b|\bwhere\b|\bwhen\b|\bNaN\b|\bsee\b"
                         r"|\(eqs? ?\d|\beqs? \d")


def declared_vars():
    """(where, name, Var) of every declared coordinate and output: the shared coordinates and each
    stage's own."""
    out = [("shared", name, var) for name, var in coords().items()]
    for st in stages().values():
        out += [(st.name, name, var) for name, var in {**st.coords, **st.outputs}.items()]
    return out


def offenders():
    bad = []
    for where, name, var in declared_vars():
        label = var.long_name
        why = []
        if len(label) > MAX_LABEL:
            why.append(f"{len(label)} characters")
        if found := EXPLANATION.search(label):
            why.append(f"explains ({found.group(0).strip()!r})")
        if why:
            bad.append(f"{where}.{name} [{', '.join(why)}]: {label}")
    return bad


def test_every_long_name_is_a_short_label():
    bad = offenders()
    assert not bad, f"{len(bad)} long_names are descriptions, not labels (move the rest to attrs['comment']):\n" + \
        "\n".join(bad)


def test_the_rule_tells_a_label_from_an_explanation():
    """The check itself: labels pass, the issue's examples do not."""
    for label in ("nominal pressure", "reference wavenumber qL", "loss tangent tan delta", "effective modulus E*"):
        assert len(label) <= MAX_LABEL and not EXPLANATION.search(label)
    for label in ("relative contact area A/A0 = erf(p / 2 sqrt G) (eq 19; with contact.correction: G -> G_eff, "
                  "attribute 'correction')", "gamma_eff (0 where gamma_eff <= 0)", "spectrum draw: 0 = the measured",
                  "mean separation u(p) (eq 57)"):
        assert len(label) > MAX_LABEL or EXPLANATION.search(label)
