"""Draw pass: rasterise every mesh into the AOVs (colour, wrinkle, normal)."""
from __future__ import annotations

import moderngl
import numpy as np

from ...method.contract import MAX_LIGHTS
from ...scene.records import CameraRecord, MeshFrame
from .. import bindings
from ..bounds import EyeBound, culled_side
from ..mipmaps import build_mipmaps
from ..resources import MeshResources
from . import bind_wave, gl_matrix, inverse, irregular, normal_matrix, set_uniforms
from .base import DrawnPass

#: the turn of the bent normal across one pixel (radians) above which a pixel shades each
#: of its multisamples (draw.glsl: SHADE_SAMPLES); below it the pixel is shaded once. The
#: pulled sheet's 4x4 box-average oracle (tests/test_render.py) read a mean error of
#: 0.00046 with every wave shaded per sample, 0.00047 at 0.02 and 0.00048 at 0.05
SAMPLE_TURN = 0.02

FLIP_Y = np.diag([1.0, -1.0, 1.0, 1.0])


def light_uniforms(lights) -> dict:
    """The uniforms of include/surface.glsl for scene/lights.py's LightRecords: up to
    MAX_LIGHTS points and directions, and one dome (the last, as Storm keeps only one)."""
    position = np.zeros((MAX_LIGHTS, 4), np.float32)
    diffuse = np.zeros((MAX_LIGHTS, 3), np.float32)
    specular = np.zeros((MAX_LIGHTS, 3), np.float32)
    ambient = np.zeros((MAX_LIGHTS, 3), np.float32)
    attenuate = np.zeros(MAX_LIGHTS, np.int32)
    spot = np.zeros((MAX_LIGHTS, 4), np.float32)
    falloff = np.zeros(MAX_LIGHTS, np.float32)
    dome_sh = np.zeros((9, 3), np.float32)
    dome = 0
    count = 0
    # returns (uniforms, whether a dome lights the frame: the DOME switch)
    for light in lights:
        if light.kind == "dome":
            dome, dome_sh = 1, np.asarray(light.dome_sh, np.float32)
            continue
        if count == MAX_LIGHTS:
            continue
        position[count, :3] = light.vector
        position[count, 3] = 0.0 if light.kind == "directional" else 1.0
        diffuse[count] = light.color
        specular[count] = light.specular
        ambient[count] = light.ambient
        attenuate[count] = int(light.attenuate)
        spot[count, :3] = light.spot_direction
        spot[count, 3] = light.spot_cutoff
        falloff[count] = light.spot_falloff
        count += 1
    return {"u_num_lights": count, "u_light_position": position, "u_light_diffuse": diffuse,
            "u_light_specular": specular, "u_light_ambient": ambient,
            "u_light_attenuate": attenuate, "u_light_spot": spot,
            "u_light_spot_falloff": falloff, "u_dome_sh": dome_sh}, bool(dome)


def material_uniforms(material) -> dict:
    """UsdPreviewSurface's inputs, or the fallback surface's displayColor and opacity."""
    surface = material.surface
    if surface is None:
        return {"u_opacity": float(material.opacity), "u_opacity_threshold": 0.0}
    return {"u_emissive_color": tuple(float(c) for c in surface.emissive_color),
            "u_use_specular_workflow": int(surface.use_specular_workflow),
            "u_specular_color": tuple(float(c) for c in surface.specular_color),
            "u_metallic": surface.metallic, "u_roughness": surface.roughness,
            "u_clearcoat": surface.clearcoat,
            "u_clearcoat_roughness": surface.clearcoat_roughness,
            "u_opacity": surface.opacity, "u_opacity_threshold": surface.opacity_threshold,
            "u_ior": surface.ior, "u_occlusion": surface.occlusion}


def normal_map_uniforms(res: MeshResources) -> dict:
    record = res.normal_map_record
    if record is None:
        return {}
    return {"u_udim_layer": res.udim_layers,
            "u_normal_scale": tuple(float(v) for v in record.scale[:4]),
            "u_normal_bias": tuple(float(v) for v in record.bias[:4])}


class DrawPass(DrawnPass):
    """Per pixel: the wave blend, the bent normal and the texture offset (draw.glsl)."""

    SHADER = "draw.glsl"
    #: the wave blend's units (include/wave.glsl) and its own
    UNITS = {**bindings.WAVE, "DRAW_DIFFUSE_TEXTURE": 2, "DRAW_CORNER_ST": 7,
             "DRAW_NORMAL_ST": 9, "DRAW_NORMAL_TEXTURE": 10, "DRAW_SHADING_NORMALS": 11,
             "DRAW_NORMAL_CORNERS": 12, "DRAW_DOME_TEXTURE": 13, "DRAW_CORNER_COLORS": 14,
             "DRAW_TRIANGLE_NEIGHBORS": 15}

    def __init__(self, ctx):
        import moderngl

        super().__init__(ctx)
        self.mode = moderngl.TRIANGLES
        self.variants()  # the paper's variant always; the other on first use
        #: where folds turn within a pixel, shade each multisample where it lies (the
        #: default; render --no-shade-samples turns it off; draw.glsl: SHADE_SAMPLES)
        self.shade_samples = False
        #: draw the folds where the view ray meets them (render --relief; draw.glsl: RELIEF)
        self.relief = False
        self.frame_uniforms: dict = {}
        self.dome_lit = False
        #: a textured dome's environment, uploaded once per file: (key, texture, levels)
        self.dome = (None, None, 0)

    def begin(self, camera: CameraRecord, lights, wrinkles: bool) -> None:
        # row-vector: view, projection, then y flipped so that GL's first row (the bottom)
        # is the image's top row and the readback needs no flip; that mirror turns the
        # winding around, so front faces are clockwise
        world_to_clip = camera.view @ camera.projection @ FLIP_Y
        self.ctx.front_face = "cw"
        self.frame_uniforms = {
            "u_world_to_clip": gl_matrix(world_to_clip),
            "u_world_to_eye": gl_matrix(camera.view),
            "u_wrinkles": int(wrinkles),
            # eye space +Z in world: the directional viewer of Storm's fallback surface
            "u_viewer_direction": tuple(float(v) for v in inverse(camera.view)[2, :3]),
        }
        lights_uniforms, self.dome_lit = light_uniforms(lights)
        self.frame_uniforms.update(lights_uniforms)
        self.frame_uniforms.update(self._dome_texture(lights))
        for variant in self.variants.programs.values():
            set_uniforms(variant.program, self.frame_uniforms)
            variant.frame_uniforms = self.frame_uniforms

    def _dome_texture(self, lights) -> dict:
        """Upload a textured dome's environment (mip-mapped) when it is new; its uniforms."""
        dome = next((light for light in reversed(lights) if light.kind == "dome"), None)
        if dome is None or dome.dome_texture is None:
            return {"u_dome_textured": 0}
        key, texture, levels = self.dome
        if key != dome.dome_key:
            if texture is not None:
                texture.release()
            pixels = np.ascontiguousarray(dome.dome_texture.linear(), np.float32)
            height, width = pixels.shape[:2]
            texture = self.ctx.texture((width, height), 4, pixels.tobytes(), dtype="f4")
            build_mipmaps(self.ctx, texture, pixels, srgb=False)
            texture.repeat_x, texture.repeat_y = True, False  # longitude wraps
            levels = int(np.floor(np.log2(max(width, height))))
            self.dome = (dome.dome_key, texture, levels)
        return {"u_dome_textured": 1, "u_dome_levels": float(levels),
                "u_world_to_dome": np.ascontiguousarray(dome.world_to_dome, np.float32),
                "u_dome_specular": tuple(float(c) for c in dome.specular)}

    def release(self) -> None:
        if self.dome[1] is not None:
            self.dome[1].release()
        self.dome = (None, None, 0)
        super().release()

    def draw(self, res: MeshResources, frame: MeshFrame, camera: CameraRecord,
             bound: EyeBound | None = None) -> None:
        """Draw one mesh; ``bound``: where its pose can be (render/bounds.py), which
        decides whether a side of it can be left out."""
        if res.num_triangles == 0 or not frame.visible:
            return
        record = res.record
        local_to_world = frame.local_to_world
        try:  # inv, not pinv: pinv's SVD was a tenth of a small frame on a GPU node
            to_local = inverse(local_to_world)
        except np.linalg.LinAlgError:  # a scale of 0 flattens the mesh
            to_local = np.linalg.pinv(local_to_world)
        eye_local = np.append(camera.position, 1.0) @ to_local
        material = record.material
        # a display override (the paint window's ramps) takes the colour's place
        display = res.display_colors is not None
        colors = res.display_colors if display else res.corner_colors
        variant = self.variants(TWO_SYSTEMS=res.waves.systems > 1,
                                IRREGULAR=irregular(res),
                                NORMAL_MAP=res.normal_map is not None,
                                FALLBACK_SURFACE=material.surface is None,
                                TEXTURED=res.texture is not None and not display,
                                DOME=self.dome_lit,
                                VERTEX_COLOR=colors is not None,
                                SHADE_SAMPLES=self.shade_samples,
                                RELIEF=self.relief,
                                MASKED=material.surface is not None and
                                material.surface.opacity_threshold > 0.0)
        if variant.frame_uniforms is not self.frame_uniforms:  # a variant made this frame
            set_uniforms(variant.program, self.frame_uniforms)
            variant.frame_uniforms = self.frame_uniforms
        set_uniforms(variant.program, {
            "u_local_to_world": gl_matrix(local_to_world),
            "u_normal_to_world": normal_matrix(local_to_world),
            "u_eye_local": tuple(float(v) for v in eye_local[:3] / eye_local[3]),
            "u_eye_world": tuple(float(v) for v in camera.position[:3]),
            "u_diffuse_color": (1.0, 1.0, 1.0) if display else
            tuple(float(c) for c in material.diffuse_color),
            "u_double_sided": int(record.double_sided),
            **material_uniforms(material),
            "u_texture_scale": tuple(float(v) for v in material.texture_scale[:4]),
            "u_texture_bias": tuple(float(v) for v in material.texture_bias[:4]),
            **normal_map_uniforms(res),
            "u_profile_curvature": res.profile_curvature,
            "u_profile_steepest": res.profile_steepest,
            "u_sample_turn": SAMPLE_TURN,
        })
        # Storm culls nothing; a side no camera can see is left out (render/bounds.py)
        side = culled_side(record, frame, camera, bound)
        if side is None:
            self.ctx.disable(moderngl.CULL_FACE)
        else:
            self.ctx.enable(moderngl.CULL_FACE)
            self.ctx.cull_face = side
        units = self.UNITS
        bind_wave(units, res, variant.program)
        if res.texture is not None and not display:
            res.texture.use(location=units["DRAW_DIFFUSE_TEXTURE"])
        if self.dome[1] is not None:
            self.dome[1].use(location=units["DRAW_DOME_TEXTURE"])
        if res.normal_map is not None:
            res.normal_map.use(location=units["DRAW_NORMAL_TEXTURE"])
        self.bind(reads={"DRAW_CORNER_ST": res.corner_st,
                         "DRAW_SHADING_NORMALS": res.shading_normals,
                         "DRAW_NORMAL_CORNERS": res.normal_corners})
        if res.normal_map is not None:
            self.bind(reads={"DRAW_NORMAL_ST": res.normal_st})
        if colors is not None:
            self.bind(reads={"DRAW_CORNER_COLORS": colors})
        if self.relief:
            self.bind(reads={"DRAW_TRIANGLE_NEIGHBORS": res.triangle_neighbors})
        variant.vao.render(mode=self.mode, vertices=3 * res.num_triangles)

