"""Studies as ``.maizeviz`` projects: light results as records, stands that keep results on
their plants, and opening a project (:mod:`maizeviz.project.study`). The archive itself (members,
limits, JSON and arrays) is :mod:`maizeviz.io.archive`, below every stage."""
