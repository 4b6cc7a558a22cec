Vertex 1 0 0 0 {normal=(0 0 1)
