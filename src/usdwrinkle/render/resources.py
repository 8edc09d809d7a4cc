"""GPU resources of one mesh: the SSBOs the passes read and write.

Created when the topology is new or changed, reused every frame after that;
per-frame data is written into the existing buffers.
"""
from __future__ import annotations

import numpy as np

from ..scene.records import MeshRecord

FIELD_FLOATS = 12  # WrinkleField: normal, wave, direction (3 x vec4)
JOINT_FLOATS = 36  # Joint: mat4 + real + dual + 3 scale rows (9 x vec4)


def vec4(points: np.ndarray, w: float | np.ndarray = 1.0) -> np.ndarray:
    """(n, 3) -> (n, 4) float32 (std430 arrays use vec4, never vec3)."""
    out = np.empty((len(points), 4), np.float32)
    out[:, :3] = points
    out[:, 3] = w
    return out


def rest_tangents(normals: np.ndarray) -> np.ndarray:
    """A deterministic unit tangent orthogonal to each rest normal, (n, 3) float32."""
    normals = np.asarray(normals, np.float64)
    axis = np.zeros_like(normals)
    use_x = np.abs(normals[:, 0]) < 0.9
    axis[use_x, 0] = 1.0
    axis[~use_x, 1] = 1.0
    tangent = axis - np.sum(axis * normals, axis=1, keepdims=True) * normals
    length = np.linalg.norm(tangent, axis=1, keepdims=True)
    return np.where(length > 1e-12, tangent / np.maximum(length, 1e-12), axis).astype(np.float32)


def topology_block(record: MeshRecord) -> tuple[np.ndarray, dict]:
    """The int SSBO of include/topology.glsl and the uniforms giving its part offsets."""
    topo = record.topology
    parts = [topo.neighbor_offsets, topo.neighbor_indices, topo.triangle_offsets,
             topo.triangle_indices, topo.triangles.reshape(-1)]
    starts = np.concatenate([[0], np.cumsum([len(p) for p in parts])])
    uniforms = {"u_neighbor_indices_base": int(starts[1]),
                "u_triangle_offsets_base": int(starts[2]),
                "u_triangle_indices_base": int(starts[3]),
                "u_triangles_base": int(starts[4])}
    return np.concatenate(parts).astype(np.int32), uniforms


def _bytes(array: np.ndarray) -> bytes:
    data = np.ascontiguousarray(array).tobytes()
    return data if data else b"\0" * 16  # GL buffers cannot be empty


class MeshResources:
    """All buffers of one mesh on the GPU."""

    def __init__(self, ctx, record: MeshRecord):
        self.ctx = ctx
        self.record = record
        n = len(record.rest_points)
        self.num_points = n
        self.num_triangles = len(record.topology.triangles)
        self.buffers = []
        self.rest_points = self._buffer(vec4(record.rest_points))
        self.posed_points = self._buffer(vec4(record.rest_points))
        topo, self.topology_uniforms = topology_block(record)
        self.topology = self._buffer(topo)
        frame = np.empty((n, 2, 4), np.float32)
        frame[:, 0, :3] = record.rest_normals
        frame[:, 0, 3] = 0.0
        frame[:, 1, :3] = rest_tangents(record.rest_normals)
        frame[:, 1, 3] = 0.0
        self.rest_frame = self._buffer(frame)
        self.q_width = self._buffer(vec4(record.params.q, record.params.width))
        # Two field buffers alternate: crush writes this frame's, the seed step reads the
        # previous frame's wave vectors to carry its phases over (phase history).
        self.field_buffers = [self._buffer(np.zeros((n, FIELD_FLOATS), np.float32))
                              for _ in range(2)]
        self.current_fields = 0
        self.anchor_phase = self._buffer(np.zeros(n, np.float32))
        #: relaxed phase per vertex (what draw and the bake read)
        self.phase = self._buffer(np.zeros(n, np.float32))
        #: unit phasors during relaxation (ping-pong) and the per-edge rotations
        self.phasors = [self._buffer(np.zeros((n, 2), np.float32)) for _ in range(2)]
        self.edge_rotations = self._buffer(
            np.zeros((len(record.topology.neighbor_indices), 4), np.float32))
        st = record.material.corner_st
        corner = np.zeros((self.num_triangles * 3, 4), np.float32)
        if st is not None:
            corner[:, :2] = st.reshape(-1, 2)
        self.corner_st = self._buffer(corner)
        self.face_normals = self._buffer(np.zeros((self.num_triangles, 4), np.float32))
        skin = record.skin
        if skin is not None:
            self.influences = skin.joint_indices.shape[1]
            self.joint_indices = self._buffer(skin.joint_indices.astype(np.int32))
            self.joint_weights = self._buffer(skin.joint_weights.astype(np.float32))
            self.joints = self._buffer(
                np.zeros((max(skin.num_joints, 1), JOINT_FLOATS), np.float32))
            subshapes = max(skin.num_subshapes, 1)
            self.subshape_offsets = self._buffer(np.zeros((subshapes * n, 4), np.float32))
            self.subshape_weights = self._buffer(np.zeros(subshapes, np.float32))
            self.uploaded_subshapes: set[int] = set()
        self.texture = None
        if record.material.texture is not None:
            tex = record.material.texture
            self.texture = ctx.texture((tex.shape[1], tex.shape[0]), 4, _bytes(tex), dtype="f4")
            self.texture.build_mipmaps()
            self.texture.repeat_x = self.texture.repeat_y = True
        self.profiles = []
        for table in (record.params.height_profile, record.params.gradient_profile):
            tex = ctx.texture((len(table), 1), 1, _bytes(table.astype(np.float32)), dtype="f4")
            tex.repeat_x = True
            tex.repeat_y = False
            self.profiles.append(tex)
        self.textures = [t for t in [self.texture, *self.profiles] if t is not None]

    def _buffer(self, array: np.ndarray):
        buf = self.ctx.buffer(_bytes(array))
        self.buffers.append(buf)
        return buf

    def upload_subshape(self, blend_shape: int, subshape: int) -> None:
        """Scatter one sub-shape's offsets into its dense row (first use only)."""
        if subshape in self.uploaded_subshapes:
            return
        skin = self.record.skin
        offsets = skin.subshape_offsets[subshape]
        row = np.zeros((self.num_points, 4), np.float32)
        ids = skin.blend_point_indices[blend_shape] if blend_shape < len(
            skin.blend_point_indices) else None
        if len(offsets):
            if ids is None:
                row[:len(offsets), :3] = offsets[:self.num_points]
            else:
                row[ids[:len(offsets)], :3] = offsets[:len(ids)]
        self.subshape_offsets.write(row.tobytes(), offset=subshape * self.num_points * 16)
        self.uploaded_subshapes.add(subshape)

    @property
    def fields(self):
        return self.field_buffers[self.current_fields]

    @property
    def previous_fields(self):
        return self.field_buffers[1 - self.current_fields]

    def read_fields(self) -> dict:
        """Read back what the passes computed (the bake's single source of truth)."""
        n = self.num_points
        fields = np.frombuffer(self.fields.read(), np.float32)[:n * FIELD_FLOATS].reshape(n, 12)
        posed = np.frombuffer(self.posed_points.read(), np.float32)[:n * 4].reshape(n, 4)
        phase = np.frombuffer(self.phase.read(), np.float32)[:n]
        return {"points": posed[:, :3].copy(), "normals": fields[:, 0:3].copy(),
                "usable": fields[:, 3] > 0.5, "wave_vector": fields[:, 4:7].copy(),
                "amplitude": fields[:, 7].copy(), "direction": fields[:, 8:11].copy(),
                "compression": fields[:, 11].copy(), "phase": phase.copy(),
                "anchor_phase": np.frombuffer(self.anchor_phase.read(), np.float32)[:n].copy()}

    def release(self) -> None:
        for buf in self.buffers:
            buf.release()
        for tex in self.textures:
            tex.release()
        self.buffers, self.textures = [], []
