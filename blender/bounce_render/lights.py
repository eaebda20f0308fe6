"""Blender's lights and world as bounce lights (docs/blender.md has the units): a point or spot
of power P watts has intensity P / 4pi W/sr, a spot times cos of the angle from its axis; a sun's strength is irradiance in W/m2; an area
light of power P over area A has radiance P / (4 A), as Cycles 3.4 renders it (measured by
bench/peers/cycles on the bunny: direct light equal to 0.04 %); the world's Background colour x strength
is the sky's radiance, an Environment Texture its lat-long image."""

import math


def _vec(v):
    return [round(float(x), 7) for x in v]


def _axes(m):
    """Position, the light's -Z (where it points) and its X and Y edges, from a bounce-space matrix."""
    return m.translation, -(m.col[2].xyz), m.col[0].xyz, m.col[1].xyz


def light_entry(name, light, m, report):
    """The scene file's light for Blender light data `light` placed by `m` (bounce space)."""
    pos, forward, x, y = _axes(m)
    colour = _vec(light.color)
    what = f"light {name}"
    if light.type in ("POINT", "SPOT"):
        entry = {"type": light.type.lower(), "name": name, "position": _vec(pos), "color": colour,
                 "intensity": light.energy / (4 * math.pi)}
        if light.shadow_soft_size > 0:
            report.add(f"{what}: radius {light.shadow_soft_size:g} rendered as a point (hard shadows)")
        if light.type == "SPOT":
            half = light.spot_size / 2
            # Cycles smooths the edge over the blend's share of the cone's cosine, and dims a spot
            # by cos(angle from its axis) (bench/peers/light_units.py).
            inner = math.acos(min(1.0, math.cos(half) + (1 - math.cos(half)) * light.spot_blend))
            entry.update({"direction": _vec(forward.normalized()), "cone_angle": math.degrees(inner),
                          "cone_falloff": max(0.0, math.degrees(half - inner)), "cosine_power": 1})
        return entry
    if light.type == "SUN":
        if light.angle > 0:
            report.add(f"{what}: angle {math.degrees(light.angle):g} degrees rendered as a sharp sun")
        return {"type": "distant", "name": name, "direction": _vec(forward.normalized()), "color": colour,
                "intensity": light.energy}
    if light.type == "AREA":
        sx = light.size
        sy = light.size_y if light.shape in ("RECTANGLE", "ELLIPSE") else light.size
        if light.shape in ("DISK", "ELLIPSE"):
            # A square (or rectangle) of the same area, centred where the disk is.
            report.add(f"{what}: a {light.shape.lower()} rendered as a rectangle of the same area")
            sx, sy = sx * math.sqrt(math.pi) / 2, sy * math.sqrt(math.pi) / 2
        edge_x, edge_y = x * sx, y * sy
        area = edge_x.cross(edge_y).length
        if area <= 0:
            report.add(f"{what}: zero area: not exported")
            return None
        corner = pos - edge_x / 2 - edge_y / 2
        # edge_u x edge_v is the side it emits on: Blender's area lights shine along their -Z.
        return {"type": "quad", "name": name, "corner": _vec(corner), "edge_u": _vec(edge_y), "edge_v": _vec(edge_x),
                "color": colour, "intensity": light.energy / (4 * area)}
    report.add(f"{what}: a {light.type.lower()} light is not one bounce has: not exported")
    return None


def world_light(world, material_export, report):
    """The sky for Blender's world (None for a black one)."""
    if world is None:
        return None
    if not world.use_nodes or world.node_tree is None:
        colour = _vec(world.color[:3])
        return {"type": "sky", "name": "world", "color": colour} if max(colour) > 0 else None
    output = next((n for n in world.node_tree.nodes if n.type == "OUTPUT_WORLD" and n.is_active_output), None)
    link = output.inputs["Surface"].links[0] if output and output.inputs["Surface"].is_linked else None
    if link is None:
        return None
    node = link.from_node
    if node.type != "BACKGROUND":
        report.add(f"world: a {node.bl_label} node is not read: no sky")
        return None
    strength = float(node.inputs["Strength"].default_value)
    sky = {"type": "sky", "name": "world", "color": _vec(node.inputs["Color"].default_value[:3]), "intensity": strength}
    colour = node.inputs["Color"]
    if colour.is_linked:
        tex = colour.links[0].from_node
        if tex.type == "TEX_ENVIRONMENT" and tex.image is not None:
            path = material_export.image_file(tex.image, "world")
            if path is None:
                return None
            if tex.inputs["Vector"].is_linked:
                report.add("world: the environment's mapping is not read")
            # Blender's equirectangular u = atan2(y, -x) / 2pi + 0.5 (Z up) is bounce's (Y up)
            # turned a quarter about the vertical.
            sky.update({"color": 1.0, "texture": path, "rotation": 90.0})
        else:
            report.add(f"world: colour fed by a {tex.bl_label} node: not read")
    return sky if strength > 0 else None
