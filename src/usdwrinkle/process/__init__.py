"""The process: errors and how they are said, warnings (log), progress, limits, memory,
stop signals, frames as people read them (timecode.py), the address space and the
package's data folders. Standard library only
(what a module here imports stays inside this room), below every other room."""
