"""The task composer configuration a Tesseract config folder carries
(``task_composer_plugins.yaml``).

Tesseract's Python wheel ships no task composer file, and its planning examples read one from a
clone of ``tesseract_planning``; this file makes the folder self-contained. It defines three
pipelines in the named-port format of Tesseract 0.28 (``tesseract-robotics`` 0.5.x), each a
chain of tasks over the data keys ``input_data`` -> ``output_data`` with ``environment`` and
``profiles``:

* ``OMPLPipeline``: minimum length, OMPL (RRTConnect by the default profile), discrete contact
  check, iterative spline time parameterisation;
* ``TrajOptPipeline``: the same with TrajOpt instead of OMPL;
* ``FreespacePipeline``: OMPL, then TrajOpt smoothing OMPL's path, then the checks.
"""

from __future__ import annotations

import itertools

PIPELINES: dict[str, tuple[tuple[str, str], ...]] = {
    "OMPLPipeline": (("OMPLMotionPlannerTask", "OMPLMotionPlannerTaskFactory"),),
    "TrajOptPipeline": (("TrajOptMotionPlannerTask", "TrajOptMotionPlannerTaskFactory"),),
    "FreespacePipeline": (("OMPLMotionPlannerTask", "OMPLMotionPlannerTaskFactory"),
                          ("TrajOptMotionPlannerTask", "TrajOptMotionPlannerTaskFactory")),
}
"""Pipeline name -> its planner tasks (node name, factory class), in order."""

LIBRARIES = ("tesseract_task_composer_factories", "tesseract_task_composer_planning_factories",
             "tesseract_task_composer_taskflow_factories")


def _ports(indent: int, program_in: str, program_out: str | None) -> list[str]:
    pad = " " * indent
    lines = [f"{pad}inputs:", f"{pad}  program: {program_in}", f"{pad}  environment: environment",
             f"{pad}  profiles: profiles"]
    if program_out is not None:
        lines += [f"{pad}outputs:", f"{pad}  program: {program_out}"]
    return lines


def _task(name: str, factory: str, program_in: str, program_out: str | None,
          extra: tuple[str, ...] = ()) -> list[str]:
    return [f"            {name}:", f"              class: {factory}", "              config:",
            "                conditional: true", *_ports(16, program_in, program_out),
            *(f"                {e}" for e in extra)]


def _pipeline(name: str, planners: tuple[tuple[str, str], ...]) -> list[str]:
    lines = [f"      {name}:", "        class: PipelineTaskFactory", "        config:",
             "          conditional: false", *_ports(10, "input_data", "output_data"),
             "          nodes:"]
    for terminal in ("DoneTask", "ErrorTask"):
        lines += [f"            {terminal}:", f"              class: {terminal}Factory",
                  "              config:", "                conditional: false"]
    # Without trigger_abort the pipeline ends at ErrorTask *successfully*: a failed planner
    # would hand back its unplanned input as a "successful" result.
    lines.append("                trigger_abort: true")
    lines += _task("MinLengthTask", "MinLengthTaskFactory", "input_data", "output_data")
    order = ["MinLengthTask"]
    for k, (node, factory) in enumerate(planners):
        seeds_next = "true" if k + 1 < len(planners) else "false"
        lines += _task(node, factory, "output_data", "output_data",
                       (f"format_result_as_input: {seeds_next}",))
        order.append(node)
    lines += _task("DiscreteContactCheckTask", "DiscreteContactCheckTaskFactory", "output_data",
                   None)
    lines += _task("IterativeSplineParameterizationTask",
                   "IterativeSplineParameterizationTaskFactory", "output_data", "output_data")
    order += ["DiscreteContactCheckTask", "IterativeSplineParameterizationTask", "DoneTask"]
    lines.append("          edges:")
    for source, after in itertools.pairwise(order):
        lines += [f"            - source: {source}",
                  f"              destinations: [ErrorTask, {after}]"]
    lines.append("          terminals: [ErrorTask, DoneTask]")
    return lines


def task_composer_yaml(threads: int = 1) -> str:
    """``task_composer_plugins.yaml``: the Taskflow executor (``threads`` worker threads) and
    the pipelines of :data:`PIPELINES`."""
    lines = ["# Tesseract task composer pipelines, written by usar-arm (Tesseract 0.28 format).",
             "task_composer_plugins:", "  search_libraries:",
             *(f"    - {lib}" for lib in LIBRARIES),
             "  executors:", "    default: TaskflowExecutor", "    plugins:",
             "      TaskflowExecutor:", "        class: TaskflowTaskComposerExecutorFactory",
             "        config:", f"          threads: {threads}",
             "  tasks:", "    plugins:"]
    for name, planners in PIPELINES.items():
        lines += _pipeline(name, planners)
    return "\n".join(lines) + "\n"
