"""The algorithms: skeletons, walls, doors, rooms, the room graph, the methods and their result.

Nothing here opens a file: every function takes arrays, grids and graphs and returns them.
"""
