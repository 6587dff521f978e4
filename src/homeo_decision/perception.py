"""From message fields to the robot's perceived world code (no rclpy).

The graph sends the world by names (robot location, object states, human presence) and
the recognised intention separately; the core works on world codes. The perceived code
is the world as reported with the *recognised* intention in place of the true one.
"""

from __future__ import annotations

from .scenario import Scenario


def world_values(sc: Scenario, world: dict, intention: str) -> dict[str, str]:
    values = {"robot.location": world["robot"]["location"], "human.presence": world["human"]["presence"],
              "intention": intention}
    for o, vars_ in world["objects"].items():
        for var, v in vars_.items():
            values[f"{o}.{var}"] = v
    return values


def perceived_code(sc: Scenario, world: dict, intention: str) -> int:
    """World code of a ``homeo/world`` payload seen with ``intention`` (raises ScenarioError)."""
    return sc.encode(world_values(sc, world, intention))


def world_fields(sc: Scenario, code: int) -> dict:
    """The ``robot``/``objects``/``human`` fields of ``homeo/world`` for a world code."""
    v = sc.view(code)
    return {
        "robot": {"location": v["robot.location"]},
        "objects": {o: {var: v[f"{o}.{var}"] for var in spec["variables"]} for o, spec in sc.objects.items()},
        "human": {"presence": v["human.presence"], "relation": v["human.relation"]},
    }


def body_vector(sc: Scenario, body: dict) -> list[float]:
    """Body readings by drive name -> a vector indexed like all drives (others 0)."""
    return [float(body.get(d.name, 0.0)) if d.source == "body" else 0.0 for d in sc.drives]
