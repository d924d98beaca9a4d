; vehicle::ictineu In location::dock (7.2.1); each location has x, y, z.
(define (problem move-to-survey)
  (:domain move)
  (:objects ictineu - vehicle
            dock survey trench - location)
  (:init (in ictineu dock)
         (= (max_depth ictineu) 30)
         (= (x dock) 0) (= (y dock) 0) (= (z dock) 0)
         (= (x survey) 40) (= (y survey) 25.5) (= (z survey) 12)
         (= (x trench) 60) (= (y trench) 10) (= (z trench) 85))
  (:goal (in ictineu survey)))
