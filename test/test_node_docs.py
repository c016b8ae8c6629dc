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
