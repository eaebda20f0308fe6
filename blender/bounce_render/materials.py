"""Blender materials as bounce materials (docs/blender.md): the Principled BSDF's base colour
and its image, roughness, metallic and specular, normal map, alpha and its image as a cutout,
emission and its image, transmission and IOR; a Diffuse BSDF's colour; an Emission shader.
What a node tree holds beyond these is named in the report."""

import os
import bpy

DEFAULT = {"color": 0.8}  # Blender's own default surface


def _linked(socket):
    return socket.links[0].from_socket if socket.is_linked and socket.links else None


def _rgb(value):
    return [round(float(c), 6) for c in value[:3]]


class MaterialExport:
    """Turns materials into the scene file's "materials" entries, writing images it needs."""

    def __init__(self, folder, report):
        self.folder = folder
        self.report = report
        self.materials = {"blender_default": dict(DEFAULT)}
        self.names = {}
        self.emissive = set()
        self.images = {}

    def name_of(self, material):
        """The bounce material for a Blender material (None: the default surface)."""
        if material is None:
            return "blender_default"
        key = material.name_full
        if key not in self.names:
            name = "".join(c if c.isalnum() or c in "-_." else "_" for c in material.name)
            while name in self.materials:
                name += "_"
            self.names[key] = name
            self.materials[name] = self._convert(material)
            if "emission" in self.materials[name]:
                self.emissive.add(name)
        return self.names[key]

    def image_file(self, image, what):
        """A file bounce can read for `image`: its own, or a copy of a packed one."""
        if image is None:
            return None
        if image.name_full in self.images:
            return self.images[image.name_full]
        if image.packed_file is not None:
            ext = os.path.splitext(image.filepath)[1] or ".png"
            path = os.path.join(self.folder, f"image{len(self.images)}{ext}")
            with open(path, "wb") as f:
                f.write(image.packed_file.data)
            self.images[image.name_full] = path
            return path
        if image.source != "FILE":
            self.report.add(f"{what}: image {image.name} is {image.source.lower()}, not a file: not read")
            return None
        path = bpy.path.abspath(image.filepath, library=image.library)
        if not os.path.isfile(path):
            self.report.add(f"{what}: image file {path} is not there: not read")
            return None
        if image.colorspace_settings.name not in ("sRGB", "Non-Color", "Linear", "Raw"):
            self.report.add(f"{what}: image {image.name} in {image.colorspace_settings.name}: read as stored")
        self.images[image.name_full] = os.path.abspath(path)
        return self.images[image.name_full]

    def _image_of(self, socket, what, want_alpha=False):
        """The image a socket is fed by, straight from an Image Texture node; else None (reported)."""
        src = _linked(socket)
        if src is None:
            return None
        node = src.node
        if node.type == "TEX_IMAGE" and (src.name == "Alpha") == want_alpha:
            if node.inputs["Vector"].is_linked:
                self.report.add(f"{what}: the texture's mapping (its Vector input) is not read")
            return self.image_file(node.image, what)
        self.report.add(f"{what}: fed by a {node.bl_label} node: not read (its default value used)")
        return None

    def _convert(self, material):
        what = f"material {material.name}"
        if not material.use_nodes or material.node_tree is None:
            return {"color": _rgb(material.diffuse_color)}
        output = next((n for n in material.node_tree.nodes if n.type == "OUTPUT_MATERIAL" and n.is_active_output), None)
        surface = _linked(output.inputs["Surface"]) if output else None
        if surface is None:
            return {"color": 0.0}  # no surface shader: black, as Cycles renders it
        node = surface.node
        if node.type == "BSDF_PRINCIPLED":
            return self._principled(node, material, what)
        if node.type == "BSDF_DIFFUSE":
            m = {"color": _rgb(node.inputs["Color"].default_value)}
            if (tex := self._image_of(node.inputs["Color"], what)) is not None:
                m["color"], m["color_texture"] = 1.0, tex
            return m
        if node.type == "EMISSION":
            strength = float(node.inputs["Strength"].default_value)
            return {"color": 0.0, "emission": [c * strength for c in _rgb(node.inputs["Color"].default_value)]}
        self.report.add(f"{what}: a {node.bl_label} shader is not one bounce reads: a grey surface instead")
        return dict(DEFAULT)

    def _principled(self, node, material, what):
        i = node.inputs
        base = _rgb(i["Base Color"].default_value)
        metallic = float(i["Metallic"].default_value)
        roughness = float(i["Roughness"].default_value)
        specular = float(i["Specular"].default_value)
        m = {"roughness": min(1.0, max(0.01, roughness))}
        tex = self._image_of(i["Base Color"], what + " base colour")
        if tex is not None:
            m["color_texture"] = tex
            base = [1.0, 1.0, 1.0]
        for socket in ("Metallic", "Roughness", "Specular"):
            if i[socket].is_linked:
                self.report.add(f"{what}: {socket} is fed by a node: its value {i[socket].default_value:g} used")
        # Diffuse = base x (1 - metallic); F0 = mix(0.08 x specular, base, metallic), as the
        # glTF reading of docs/scene-format.md.
        m["color"] = [c * (1 - metallic) for c in base]
        m["specular"] = [0.08 * specular * (1 - metallic) + c * metallic for c in base]
        if (normal := _linked(i["Normal"])) is not None:
            if normal.node.type == "NORMAL_MAP":
                tex = self._image_of(normal.node.inputs["Color"], what + " normal map")
                if tex is not None:
                    m["normal_texture"] = tex
                    m["bump_strength"] = float(normal.node.inputs["Strength"].default_value)
            else:
                self.report.add(f"{what}: Normal fed by a {normal.node.bl_label} node: not read")
        self._alpha(i["Alpha"], material, what, m)
        emission = [c * float(i["Emission Strength"].default_value) for c in _rgb(i["Emission"].default_value)]
        tex = self._image_of(i["Emission"], what + " emission")
        if tex is not None:
            m["emission_texture"] = tex
            emission = [float(i["Emission Strength"].default_value)] * 3
        if max(emission) > 0:
            m["emission"] = emission
        transmission = float(i["Transmission"].default_value)
        if transmission > 0:
            m["transmission"] = [c * transmission for c in base]
            m["ior"] = min(3.0, max(1.0, float(i["IOR"].default_value)))
        for socket in ("Subsurface", "Sheen", "Clearcoat"):
            if float(i[socket].default_value) > 0:
                self.report.add(f"{what}: {socket} is not read")
        return m

    def _alpha(self, socket, material, what, m):
        tex = self._image_of(socket, what + " alpha", want_alpha=True)
        value = float(socket.default_value)
        if tex is None and (socket.is_linked or value >= 1):
            return
        m["alpha_mode"] = "mask" if material.blend_method == "CLIP" else "blend"
        if material.blend_method == "CLIP":
            m["alpha_cutoff"] = float(material.alpha_threshold)
        if tex is not None:
            m["opacity_texture"] = tex
        else:
            m["opacity"] = value
