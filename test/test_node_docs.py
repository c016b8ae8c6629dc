"""docs/node.md's parameter table is the one generated from config.PARAMETERS (no ROS needed)."""

from pathlib import Path

from catenary_monitor.core.config.parameters import parameters_markdown

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / 'README.md'
NODE_DOC = ROOT / 'docs' / 'node.md'


def test_node_doc_parameter_table_is_generated_from_the_parameter_table():
    text = NODE_DOC.read_text(encoding='utf-8')
    begin, end = '<!-- parameters:begin -->\n', '<!-- parameters:end -->'
    assert begin in text and end in text
    table = text.split(begin, 1)[1].split(end, 1)[0]
    assert table == parameters_markdown(), 'regenerate with config.parameters_markdown()'
    assert 'docs/node.md#parameters-and-params-files' in README.read_text(encoding='utf-8')


def test_core_and_node_cli_import_without_rclpy():
    import subprocess
    import sys

    code = (
        "import sys; sys.modules['rclpy'] = None\n"
        "import catenary_monitor.cli.main, catenary_monitor.ros.simulator\n"
        "import catenary_monitor.core.rules.health\n"
        "import catenary_monitor.core.config.parameters, catenary_monitor.core.alarms.latches\n"
    )
    subprocess.run(
        [sys.executable, '-c', code],
        check=True,
        env={'PYTHONPATH': str(README.parent), 'PATH': '/usr/bin:/bin'},
    )


def _outputs_table() -> list[tuple[int, str, str]]:
    """(index, field, meaning) of docs/node.md's outputs table."""
    text = NODE_DOC.read_text(encoding='utf-8')
    begin, end = '<!-- outputs:begin -->\n', '<!-- outputs:end -->'
    assert begin in text and end in text
    rows = text.split(begin, 1)[1].split(end, 1)[0].splitlines()[2:]
    cells = [[c.strip() for c in row.strip('|').split('|')] for row in rows if row.strip()]
    return [(int(c[0]), c[1].strip('`'), c[3]) for c in cells]


def test_node_doc_outputs_table_is_the_codes_output_fields():
    """The outputs are listed once, in docs/node.md, in the code's order and no more or less."""
    from catenary_monitor.core.monitor.state import OUTPUT_FIELDS

    table = _outputs_table()
    assert [i for i, _, _ in table] == list(range(len(table)))
    assert tuple(field for _, field, _ in table) == OUTPUT_FIELDS


def test_node_doc_sensor_state_codes_are_the_codes():
    from catenary_monitor.core.rules.sensor_state import LINE_STATES

    meaning = {field: text for _, field, text in _outputs_table()}['sensor_state']
    assert meaning.count('`') // 2 >= len(LINE_STATES)
    for code, word in enumerate(LINE_STATES):
        assert f'{code} `{word}`' in meaning, (code, word)
