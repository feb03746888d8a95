"""Seed examples of pybullet_fleet.config_utils (load_config, dataclass_from_dict, ...)."""

import enum
from dataclasses import dataclass

import pybullet
from parity_trace import Trace, call_safely
from pybullet_fleet.agent import Agent, AgentSpawnParams
from pybullet_fleet.config_utils import (
    dataclass_from_dict,
    forward_spawn_params,
    load_config,
    load_yaml_config,
    merge_configs,
    resolve_class,
)
from pybullet_fleet.core_simulation import MultiRobotSimulationCore, SimulationParams
from pybullet_fleet.geometry import Pose

T = Trace()
with open("config.yaml", "w") as fh:
    fh.write("simulation:\n  timestep: 0.1\n  gui: false\nentities: []\n")
with open("100robots_config.yaml", "w") as fh:
    fh.write("simulation:\n  timestep: 0.05\n")
with T.probe("load_config") as out:
    # Single config
    config = load_config("config.yaml")
    out["single"] = config
    # Multiple configs (100robots_config overrides config.yaml)
    config = load_config(["config.yaml", "100robots_config.yaml"])
    out["merged"] = config
    out["missing"] = call_safely(load_yaml_config, "nope.yaml")["error"].split(":")[0]
    out["merge_configs"] = merge_configs({"a": {"b": 1, "c": 2}}, {"a": {"c": 3}, "d": 4})
with T.probe("dataclass_from_dict") as out:

    class MyEnum(enum.Enum):
        A = "a"
        B = "b"

    @dataclass
    class MyParams:
        x: float = 0.0
        mode: MyEnum = MyEnum.A

    params = dataclass_from_dict(MyParams, {"x": 1.5, "mode": "b"})
    assert params.x == 1.5
    assert params.mode == MyEnum.B
    out["ok"] = True
    out["unknown_key"] = call_safely(lambda: dataclass_from_dict(MyParams, {"x": 1.5, "y": 2}).x)
with T.probe("forward_spawn_params") as out:
    sim = MultiRobotSimulationCore(SimulationParams(gui=False, monitor=False, target_rtf=0))
    spawn_params = AgentSpawnParams(
        urdf_path="robots/mobile_robot.urdf", initial_pose=Pose.from_xyz(1, 2, 0.05)
    )
    kwargs = forward_spawn_params(
        Agent.from_urdf,
        spawn_params,
        aliases={"initial_pose": "pose"},
        extra_kwargs={"sim_core": sim},
    )
    agent = Agent.from_urdf(**kwargs)
    out["kwargs"] = sorted(kwargs)
    out["pose"] = agent.get_pose().position
    pybullet.disconnect(physicsClientId=sim.client)
with T.probe("resolve_class") as out:
    out["ok"] = resolve_class("collections.OrderedDict").__name__
    out["bad"] = call_safely(resolve_class, "nodots")
T.dump()
