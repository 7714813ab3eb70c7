"""Where light comes from: clock times and dates, the sun's position, discretised skies,
Perez's split of diffuse light, and irradiance over a day or a weather file's period."""
