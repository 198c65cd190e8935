;;;; tools/demo.lisp -- load luv-physics and run a scene of the page (make demo, SCENE=basin by
;;;; default: the main job).

(load (merge-pathnames "boot.lisp" *load-truename*))

(in-package #:cl-user)

(when (luv-load-systems "luv-physics/workshop")
  (sb-ext:exit :code 2))

(let ((run (find-symbol "RUN-DEFAULT-SCENE" '#:luv-physics))
      (scene (intern (string-upcase (or (sb-ext:posix-getenv "SCENE") "basin")) :keyword)))
  (handler-case (funcall run :scene scene)
    (error (e)
      (format *error-output* "demo: ~A~%" e)
      (sb-ext:exit :code 1))))
