"""`python3 -m asg_analysis docs`: every generated block of README.md and docs/ has one writer, and a
writer finds its block stale or writes it (issue #94). The whole `docs --check` runs every study and
takes minutes; the pages' own tests check each block's figures, so here each kind of slip is shown
on made-up pages, and the real pages' blocks are held to the table without running the writers."""

import os

from asg_analysis import docs


def test_every_block_of_the_pages_has_one_writer_and_every_writer_its_block():
    problems = docs.unowned(docs.writers(), docs.page_blocks())
    assert problems == {"no writer": [], "two writers": [], "not on its page": []}
    names = [n for _, n in docs.page_blocks()]
    assert "answer" in names and "params:scene_worker" in names and "twins" in names  # each marker style is read


def page(root, name, text):
    path = os.path.join(root, name)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)
    return path


def test_a_block_with_no_writer_two_writers_or_a_lost_block_is_named(tmp_path):
    root = str(tmp_path)
    page(root, "README.md", "x\n<!-- a: begin -->\n1\n<!-- a: end -->\n")
    page(
        root,
        "docs/g.md",
        "<!-- b:begin (by hand) -->\n2\n<!-- b:end -->\n<!-- params:n:begin -->\n3\n<!-- params:n:end -->\n",
    )
    found = docs.page_blocks(root)
    assert found == [("README.md", "a"), ("docs/g.md", "b"), ("docs/g.md", "params:n")]
    one = docs.Writer("w1", [("README.md", "a"), ("docs/g.md", "b")], lambda check: 0)
    two = docs.Writer("w2", [("docs/g.md", "b"), ("docs/g.md", "gone")], lambda check: 0)
    problems = docs.unowned([one, two], found, checked={})
    assert problems["no writer"] == [("docs/g.md", "params:n")]
    assert problems["two writers"] == [(("docs/g.md", "b"), ["w1", "w2"])]
    assert problems["not on its page"] == [("docs/g.md", "gone")]


def test_a_table_writer_finds_its_block_stale_then_writes_it_keeping_the_pages_markers(tmp_path):
    path = page(str(tmp_path), "p.md", "head\n<!-- t:begin (generated) -->\nold\n<!-- t:end -->\ntail\n")
    w = docs.table(path, "t", lambda: "new\n")
    assert w.write(True) == 1  # --check: stale, nothing written
    assert "old" in open(path, encoding="utf-8").read()
    assert w.write(False) == 0 and w.write(True) == 0
    assert open(path, encoding="utf-8").read() == "head\n<!-- t:begin (generated) -->\nnew\n<!-- t:end -->\ntail\n"


def test_an_inline_block_stays_in_its_line_and_a_missing_block_is_an_error(tmp_path, capsys):
    path = page(str(tmp_path), "p.md", "chose <!-- c: begin -->a 1<!-- c: end --> then\n")
    assert docs.table(path, "c", lambda: "b 2", inline=True).write(False) == 0
    assert open(path, encoding="utf-8").read() == "chose <!-- c: begin -->b 2<!-- c: end --> then\n"
    assert docs.table(path, "nope", lambda: "x").write(True) == 2
    assert "no block 'nope'" in capsys.readouterr().err
    assert docs.table(path, "c", lambda: (_ for _ in ()).throw(ValueError("no data"))).write(True) == 2


def test_the_tables_read_from_the_code_are_in_step_on_the_real_pages():
    # the cheap writers run here (no study, no binary): each finds its block in step
    for w in docs.table_writers():
        if w.name.startswith("table params:") and w.blocks[0][1].split(":")[1] in {n for _, n in docs.PRINTED}:
            continue  # the C++ nodes' tables need the built binaries (tests/test_node_parameters.py)
        assert w.write(True) == 0, f"{w.name} is stale: python3 -m asg_analysis docs"


def test_a_new_generated_source_without_its_line_is_refused(monkeypatch):
    gen = docs.generated_sources()
    assert set(gen) == set(docs.GENERATED_FROM)
    monkeypatch.setattr(docs, "generated_sources", lambda: dict(gen, **{"catkin_ws/src/x/new.hpp": "m"}))
    w = [w for w in docs.table_writers() if w.name == "table generated sources"][0]
    assert w.write(True) == 2
